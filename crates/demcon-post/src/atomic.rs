//! Atomic file output: write a temporary file beside the target, then rename it over the
//! target, so a reader never sees a half-written file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::PostError;

/// Writes `path` through `fill` into a temporary file in the same folder, then renames it.
/// On failure the temporary file is removed and the target is left as it was.
pub(crate) fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), PostError> {
    let io = |source| PostError::Io {
        action: "writing",
        path: path.to_path_buf(),
        source,
    };
    let name = path.file_name().ok_or_else(|| {
        PostError::invalid(
            "path",
            path.display(),
            "a file path (it names a folder or nothing)",
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        w.flush()?;
        drop(w);
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}
