//! Writing one `.vtu` (or a `.pvtu` piece) atomically: the header and the appended block.

use crate::output::atomic::write_atomic_with;
use crate::output::vtu::raw;
use crate::output::vtu::view::validate_view;
use crate::output::vtu::View;
use crate::output::vtu::VtuBuffer;
use crate::output::OutputError;
use std::io::Write as _;
use std::path::Path;

/// Validates `frame` and writes it to `path` atomically (raw appended binary, zlib-compressed
/// at `compression_level` if > 0): the XML header and the appended block built in `buffer`,
/// written one after the other.
pub(crate) fn write_vtu<const D: usize>(
    path: &Path,
    frame: &View<D>,
    compression_level: u32,
    buffer: &mut VtuBuffer,
) -> Result<(), OutputError> {
    validate_view(path, frame)?;
    let header = raw::encode(frame, compression_level, buffer);
    write_atomic_with(path, |w| {
        w.write_all(header.as_bytes())
            .and_then(|()| w.write_all(&buffer.data))
            .and_then(|()| w.write_all(raw::RAW_FOOTER.as_bytes()))
            .map_err(|e| OutputError::write(path, e))
    })
}
