//! Reading input files: every scene, network, frame, table and shard is
//! read through [`read_input`], which refuses a file larger than any input
//! can be before reading it all.

use std::io::Read;
use std::path::Path;

/// Largest input file read, bytes: a network of 10⁵ nodes is ~20 MB.
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// Reads the text file `path`, refusing one larger than
/// [`MAX_INPUT_BYTES`] before reading it all (`/dev/zero` read 4 GB).
///
/// # Errors
/// The file cannot be read, is too large, or is not UTF-8.
pub fn read_input(path: &Path) -> std::io::Result<String> {
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(MAX_INPUT_BYTES + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > MAX_INPUT_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "larger than {} MiB, the most an input file may be",
                MAX_INPUT_BYTES >> 20
            ),
        ));
    }
    Ok(text)
}
