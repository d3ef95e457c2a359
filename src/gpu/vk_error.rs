//! The mapping of a failed Vulkan call to the crate's [`Error`], shared by every file of
//! `gpu/`.

use crate::error::Error;
use ash::vk;

/// Maps a failed `vk::Result` of `call` to [`Error::Vulkan`].
pub(crate) fn vk_error(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| Error::Vulkan {
        call,
        result,
        chunk: None,
    }
}
