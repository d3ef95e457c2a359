"""The exceptions vkbrdf raises: each is a :class:`vkbrdf.Error` and also the built-in
exception a Python user would catch for that kind of problem."""

import errno as _errno
import os as _os


class Error(Exception):
    """Base class of every error vkbrdf raises (besides ``KeyboardInterrupt``)."""


class MaterialError(Error, ValueError):
    """A materials file or text that does not parse or validate.

    The message is the CLI's (``FILE:LINE: material `NAME`: key `KEY`: what is wrong``);
    the attributes ``source``, ``line``, ``material`` and ``key`` carry its parts (``None``
    where unknown)."""

    source = None
    line = None
    material = None
    key = None


class BatchError(Error, ValueError):
    """A tuple array that cannot be evaluated: wrong shape, a material index outside the
    table, a missing tangent for an anisotropic material, or (``strict=True``) invalid
    tuples (then ``invalid``, ``total`` and ``first_invalid`` are set)."""

    invalid = None
    total = None
    first_invalid = None


class DeviceError(Error, RuntimeError):
    """No usable Vulkan driver or device, a Vulkan call that failed, or a request the
    engine cannot honour."""


class TableError(Error, ValueError):
    """A table that cannot be computed: an empty or oversized grid, an unknown material,
    an illegal model (e.g. ``smith-fast`` without ``beckmann``)."""


class UsageError(Error, ValueError):
    """A keyword argument with a value vkbrdf does not accept (an unknown backend name,
    precision, distribution...)."""


class FileError(Error, OSError):
    """A file that cannot be read (``errno``, ``strerror`` and ``filename`` set as on any
    ``OSError``)."""


class FileMissingError(FileError, FileNotFoundError):
    """A file that does not exist (also a ``FileNotFoundError``)."""


class FilePermissionError(FileError, PermissionError):
    """A file that may not be read (also a ``PermissionError``)."""


def file_error(code, message, filename):
    """The FileError for OS error number ``code`` (``None`` when the problem is not an OS
    error) on ``filename``: used by the native module."""
    if code is None:
        return FileError(f"{filename}: {message}")
    if code == _errno.ENOENT:
        cls = FileMissingError
    elif code in (_errno.EACCES, _errno.EPERM):
        cls = FilePermissionError
    else:
        cls = FileError
    return cls(code, _os.strerror(code), filename)


for _cls in (Error, MaterialError, BatchError, DeviceError, TableError, UsageError,
             FileError, FileMissingError, FilePermissionError):
    _cls.__module__ = "vkbrdf"
del _cls
