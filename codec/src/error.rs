//! One error enum for the crate. Every variant names what was wrong and
//! where, so a bad file or a bad input can be diagnosed from the message.

use thiserror::Error;

/// Everything the encoder, the container parser and the decoder can reject.
#[derive(Debug, Error)]
pub enum CodecError {
    /// An input texture holds a NaN or an infinity.
    #[error(
        "texture (object {object}, layer {layer}): non-finite value {value} at sample {sample}, element {element}"
    )]
    NonFinite {
        object: u32,
        layer: u32,
        sample: usize,
        element: usize,
        value: f32,
    },
    /// An input texture's description is inconsistent.
    #[error("texture (object {object}, layer {layer}): {what}")]
    BadInput {
        object: u32,
        layer: u32,
        what: String,
    },
    /// The encode input as a whole is unusable (empty, duplicate ids, bad target).
    #[error("encode input: {0}")]
    BadRequest(String),
    /// The byte budget cannot hold even the container's fixed structure.
    #[error("byte budget {budget} is below the container's minimum of {minimum} bytes")]
    BudgetTooSmall { budget: u64, minimum: u64 },

    /// The file is shorter than its header says it is: cut off (a copy or
    /// a download that stopped), not corrupt. `len` is the file's length.
    #[error("truncated: {} bytes, but {implied}", Grouped(*len))]
    TruncatedFile { len: u64, implied: Implied },
    /// The bytes ended before a field could be read.
    #[error("truncated container: {field} needs {needed} bytes at offset {offset}, file has {len}")]
    Truncated {
        field: &'static str,
        offset: u64,
        needed: u64,
        len: u64,
    },
    /// The first four bytes are not the container's magic.
    #[error("not a codec container: magic {got:02x?}, expected {expected:02x?}")]
    BadMagic { got: [u8; 4], expected: [u8; 4] },
    /// The container was written by another format version.
    #[error(
        "container format version {got} is not supported (this decoder reads version {expected}); re-encode the scene"
    )]
    VersionMismatch { got: u32, expected: u32 },
    /// A header field holds a value outside its allowed range.
    #[error("container header: field {field} = {got}, expected {expected}")]
    BadField {
        field: &'static str,
        got: u64,
        expected: String,
    },
    /// The header checksum does not match its bytes.
    #[error("container header checksum mismatch: stored {stored:08x}, computed {computed:08x}")]
    HeaderChecksum { stored: u32, computed: u32 },
    /// A block index entry overlaps the header or ends past any file's end
    /// (one merely past this file's end makes it [`CodecError::TruncatedFile`]).
    #[error("block {block}: range {offset}..{end} lies outside the payload area {start}..{len}")]
    BlockOutOfRange {
        block: usize,
        offset: u64,
        end: u64,
        start: u64,
        len: u64,
    },
    /// A block's bytes do not match its checksum.
    #[error("block {block}: checksum mismatch, stored {stored:08x}, computed {computed:08x}")]
    BlockChecksum {
        block: usize,
        stored: u32,
        computed: u32,
    },
    /// A block's own structure is inconsistent.
    #[error("block {block}: {what}")]
    BadBlock { block: usize, what: String },
    /// The entropy-coded data of one image is corrupt.
    #[error("block {block}, stream {stream}: corrupt entropy-coded data ({what})")]
    CorruptStream {
        block: usize,
        stream: usize,
        what: &'static str,
    },
    /// The declared uncompressed size is implausibly large for the file.
    #[error(
        "container declares {declared} raw bytes from a {file_len}-byte file (more than {max_ratio}:1)"
    )]
    ImplausibleSize {
        declared: u64,
        file_len: u64,
        max_ratio: u64,
    },

    /// The caller asked for something the container does not hold.
    #[error("no texture for object {object}, layer {layer}")]
    NoSuchTexture { object: u32, layer: u32 },
    /// A report's reference maps are not the ones the container holds.
    #[error(
        "texture (object {object}, layer {layer}): the container holds {container}, the reference maps {maps} (expected the maps it was encoded from)"
    )]
    ReferenceMismatch {
        object: u32,
        layer: u32,
        container: String,
        maps: String,
    },
    /// A sample, face or MIP index is out of range.
    #[error("{what} index {got} out of range 0..{limit}")]
    IndexOutOfRange {
        what: &'static str,
        got: u64,
        limit: u64,
    },
    /// The caller's output slice has the wrong length.
    #[error("output slice holds {got} elements, expected {expected}")]
    OutputSize { got: usize, expected: usize },

    /// Reading or writing a file failed. The message is complete on one
    /// line, the OS's reason included, so `cause` is not also exposed as
    /// `source()` (anyhow's `{:#}` would print it twice).
    #[error("{path}: {cause}")]
    Io { path: String, cause: std::io::Error },
    /// What was wrong with the container file at `path`
    /// ([`crate::Container::open`] names the file in every error).
    #[error("{path}: {cause}")]
    File {
        path: String,
        cause: Box<CodecError>,
    },
    #[error("baseline {name}: {what}")]
    Baseline { name: &'static str, what: String },
}

impl CodecError {
    /// The error itself, without the file it was found in.
    pub fn inner(&self) -> &CodecError {
        match self {
            CodecError::File { cause, .. } => cause.inner(),
            e => e,
        }
    }
}

/// How long a truncated file should be, by its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Implied {
    /// Too short for even the smallest header
    /// ([`crate::container::MIN_HEADER`] bytes).
    MinimumHeader,
    /// The header's own length (its `header_len` field).
    Header(u64),
    /// The block index's entry that ends last: `end` is one past its last byte.
    Block { block: usize, end: u64 },
}

impl std::fmt::Display for Implied {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Implied::MinimumHeader => write!(
                f,
                "a container's header alone is at least {} bytes",
                Grouped(crate::container::MIN_HEADER as u64)
            ),
            Implied::Header(n) => write!(f, "its header alone is {} bytes", Grouped(n)),
            Implied::Block { block, end } => {
                write!(f, "block {block} ends at byte {}", Grouped(end))
            }
        }
    }
}

/// A count written with thousands separators: 3538709 as "3,538,709".
pub struct Grouped(pub u64);

impl std::fmt::Display for Grouped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let digits = self.0.to_string();
        let mut out = String::with_capacity(digits.len() + digits.len() / 3);
        for (i, d) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                out.push(',');
            }
            out.push(d);
        }
        f.pad(&out)
    }
}

pub type Result<T> = std::result::Result<T, CodecError>;
