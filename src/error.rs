//! The library's one error type: every variant names what went wrong and where
//! (file, line, material, key, row, Vulkan call), so the CLI can print it as is.

use std::path::PathBuf;

/// Everything that can go wrong in the library. Never a panic on user input.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A materials file (or preset) that does not parse or validate.
    #[error(transparent)]
    Material(#[from] MaterialError),

    /// A tuple batch (`.npy` file or in-memory array) that cannot be evaluated.
    #[error("{path}: {message}")]
    Batch {
        /// The file, or `<memory>` for an in-memory batch.
        path: PathBuf,
        /// What is wrong, naming the first bad row where there is one.
        message: String,
    },

    /// Reading or writing a file failed.
    // The OS error is the `source`; the CLI prints the chain (`{:#}`), so the message
    // names only the path, and the pair reads "PATH: OS ERROR" once.
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },

    /// An output that cannot be written without harm (the same file as an input or as
    /// another output, a directory, a missing or read-only directory); found before any work.
    #[error("{}: {message}", path.display())]
    Output {
        /// The output as given.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// The operation was cancelled through its [`crate::cancel::Cancel`] token (the CLI:
    /// SIGINT or SIGTERM); nothing was written.
    #[error("cancelled; nothing was written")]
    Cancelled,

    /// `--strict` was asked for and some tuples were invalid.
    #[error("{invalid} of {total} tuples are invalid (zero or non-finite L, V, N, or a bad tangent); first invalid row: {first_row}")]
    InvalidTuples {
        /// Number of invalid tuples.
        invalid: u64,
        /// Number of tuples in the batch.
        total: u64,
        /// Index of the first invalid row.
        first_row: u64,
    },

    /// A Vulkan call failed. The message names the call and the result code, the chunk of
    /// the batch it failed in (when it failed during a batch), and what to try for a lost
    /// device, a hung one or exhausted memory.
    #[error("{}", render_vulkan(call, *result, chunk.as_ref()))]
    Vulkan {
        /// The API call, e.g. `vkCreateDevice`.
        call: &'static str,
        /// The result code the driver returned (`ERROR_DEVICE_LOST`, `TIMEOUT`, …).
        result: ash::vk::Result,
        /// The chunk of a streamed evaluation that failed, when the call served one.
        chunk: Option<FailedChunk>,
    },

    /// No usable Vulkan driver or device.
    #[error("{0}")]
    NoDevice(String),

    /// A shader failed to compile (names file and line).
    #[error("shader compilation failed:\n{0}")]
    Shader(String),

    /// A request the backend cannot honour (e.g. a batch too large for memory).
    #[error("{0}")]
    Unsupported(String),

    /// A table that cannot be generated, written or read (`vkbrdf table`): an empty or
    /// oversized grid, an unknown material, a file that is not in the expected layout.
    /// The message names the file or option at fault.
    #[error("{0}")]
    Table(String),

    /// A job whose buffers, sized by its input (a table's size, a batch's rows), would not
    /// fit in the memory available: refused before anything is allocated. The message
    /// names what and how much.
    #[error("{0}")]
    Memory(String),
}

/// Where in a batch a Vulkan call failed: the chunk (0-based, of `count`), the batch rows it
/// held, and the memory budget the chunks were sized for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FailedChunk {
    /// 0-based index of the chunk.
    pub index: u64,
    /// Chunks in the batch.
    pub count: u64,
    /// Batch rows of the chunk.
    pub rows: std::ops::Range<u64>,
    /// `VulkanOptions::max_gpu_memory` (`--max-gpu-memory`) of the backend, in bytes.
    pub max_gpu_memory: u64,
}

impl Error {
    /// The Vulkan result code, when this is a Vulkan error.
    pub fn vk_result(&self) -> Option<ash::vk::Result> {
        match self {
            Error::Vulkan { result, .. } => Some(*result),
            _ => None,
        }
    }

    /// A Vulkan error that names no chunk yet, now naming `chunk`; any other error as is.
    pub fn in_chunk(self, chunk: FailedChunk) -> Error {
        match self {
            Error::Vulkan {
                call,
                result,
                chunk: None,
            } => Error::Vulkan {
                call,
                result,
                chunk: Some(chunk),
            },
            other => other,
        }
    }
}

/// `Vulkan: CALL failed: RESULT[ in chunk i of n (rows a..b)]: what it means and what to
/// try` for the codes a user can act on; `RESULT (the driver's text)` for the others.
fn render_vulkan(call: &str, result: ash::vk::Result, chunk: Option<&FailedChunk>) -> String {
    use ash::vk::Result as R;
    let mut s = format!("Vulkan: {call} failed: {result:?}");
    if let Some(c) = chunk {
        s += &format!(
            " in chunk {} of {} (rows {}..{})",
            c.index, c.count, c.rows.start, c.rows.end
        );
    }
    let budget = chunk.map_or(String::new(), |c| {
        format!(
            " (now {}; e.g. --max-gpu-memory {})",
            bytes(c.max_gpu_memory),
            bytes((c.max_gpu_memory / 2).max(1))
        )
    });
    let advice = match result {
        R::ERROR_DEVICE_LOST => "the device was lost (a driver crash, a GPU reset or a hang). Check the driver and the device (`vkbrdf devices`, the kernel log, a driver update), then retry; --device picks another device, --backend cpu the CPU reference".to_string(),
        R::ERROR_OUT_OF_DEVICE_MEMORY | R::ERROR_OUT_OF_HOST_MEMORY => {
            let which = if result == R::ERROR_OUT_OF_DEVICE_MEMORY {
                "device"
            } else {
                "host"
            };
            format!("out of {which} memory. Try a smaller --max-gpu-memory{budget} (VulkanOptions::max_gpu_memory in the library), or free memory other programs hold")
        }
        R::TIMEOUT => "a chunk did not finish within the wait limit (a hung device?). Check the driver and the device, then retry, or use a smaller --max-gpu-memory for shorter chunks".to_string(),
        // No advice of our own: the driver's description of the code.
        _ => return format!("{s} ({result})"),
    };
    format!("{s}: {advice}")
}

/// `n` bytes in the units `--max-gpu-memory` reads (K, M, G: binary multiples).
fn bytes(n: u64) -> String {
    for (unit, size) in [("G", 1u64 << 30), ("M", 1 << 20), ("K", 1 << 10)] {
        if n >= size && n.is_multiple_of(size) {
            return format!("{}{unit}", n / size);
        }
    }
    n.to_string()
}

/// A problem in a materials definition: names the source, line, material and key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", self.render())]
pub struct MaterialError {
    /// File name (or `preset NAME`) the definition came from.
    pub source_name: String,
    /// 1-based line of the offending key or table, when known.
    pub line: Option<usize>,
    /// Name of the material, when known.
    pub material: Option<String>,
    /// The key at fault, when there is one.
    pub key: Option<String>,
    /// What is wrong and what would be right.
    pub message: String,
}

impl MaterialError {
    fn render(&self) -> String {
        let mut s = self.source_name.clone();
        if let Some(line) = self.line {
            s += &format!(":{line}");
        }
        s += ": ";
        if let Some(m) = &self.material {
            s += &format!("material `{m}`: ");
        }
        if let Some(k) = &self.key {
            s += &format!("key `{k}`: ");
        }
        s + &self.message
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
