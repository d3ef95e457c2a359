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

    /// A Vulkan call failed.
    #[error("Vulkan: {call} failed: {result}")]
    Vulkan {
        /// The API call, e.g. `vkCreateDevice`.
        call: &'static str,
        /// The result code the driver returned.
        result: String,
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
