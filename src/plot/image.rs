//! The image file of `busnoop plot`: its name checked before the capture is read, and the
//! finished image written whole (through a temporary file beside it) or into a FIFO or device.

use std::path::{Path, PathBuf};

use crate::exit::Failure;

/// The image formats `busnoop plot` writes, by the file's extension (any case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ImageFormat {
    Svg,
    Png,
}

impl ImageFormat {
    pub(super) fn of(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?;
        if ext.eq_ignore_ascii_case("svg") {
            Some(ImageFormat::Svg)
        } else if ext.eq_ignore_ascii_case("png") {
            Some(ImageFormat::Png)
        } else {
            None
        }
    }
}

pub(super) const IMAGE_NAMES: &str =
    "plot writes .svg or .png: name the file FLIGHT.svg or FLIGHT.png";

/// Checks the image's name before the capture is read: the image is drawn only at the end, and
/// finding then that it cannot be would waste the whole input (a pipe cannot be read twice). A
/// name without `.svg`/`.png` is a usage error (exit 2). Its folder is checked with the other
/// outputs' before the input is opened (`cli::run_capture`).
pub fn check(path: &Path) -> Result<(), Failure> {
    if ImageFormat::of(path).is_none() {
        return Err(Failure::Usage(format!(
            "-o {}: {IMAGE_NAMES}",
            path.display()
        )));
    }
    // The image goes to a temporary file beside it, renamed over it at the end: the folder must
    // take a new file, and an image already there must be writable (a FIFO, a device: written
    // directly). Found only after decoding, the whole input was wasted.
    if special(path) {
        return Ok(());
    }
    let cannot =
        |e: std::io::Error| Failure::Output(format!("cannot create {}: {e}", path.display()));
    if std::fs::symlink_metadata(path).is_ok() {
        std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(cannot)?;
    }
    let (probe, _) = temporary(path).map_err(cannot)?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// A FIFO, a device or another file that is not a regular file (or a link to one): written
/// directly, never replaced.
pub(super) fn special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file())
}

/// A new file beside `path` for the image (`.NAME.busnoop-PID-N.tmp`), created exclusively;
/// renamed over `path` once whole.
pub(super) fn temporary(path: &Path) -> std::io::Result<(PathBuf, std::fs::File)> {
    use std::os::unix::fs::OpenOptionsExt;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map_or_else(|| "plot".into(), |n| n.to_string_lossy().into_owned());
    let mut n = 0u32;
    loop {
        let tmp = dir.join(format!(".{name}.busnoop-{}-{n}.tmp", std::process::id()));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o644)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 1000 => n += 1,
            Err(e) => return Err(e),
        }
    }
}

/// Writes the finished image to `path`: a regular file (or a new name) through a temporary file
/// beside it, renamed over it, so that a full disk or a kill leaves the old image whole and no
/// cut one; a FIFO or device directly, opened so that SIGINT/SIGTERM end the wait for a FIFO's
/// reader ([`crate::files::create_file`]).
pub(super) fn write_image(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    use std::io::Write;
    let failed =
        |e: std::io::Error| Failure::Output(format!("cannot write {}: {e}", path.display()));
    if special(path) {
        let mut f = crate::files::create_file(path)
            .map_err(|e| Failure::from_create(&format!("cannot create {}", path.display()), &e))?;
        return f.write_all(bytes).map_err(failed);
    }
    let (tmp, mut f) = temporary(path)
        .map_err(|e| Failure::Output(format!("cannot create {}: {e}", path.display())))?;
    let written = f
        .write_all(bytes)
        .and_then(|()| f.sync_all())
        .and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(failed(e));
    }
    Ok(())
}

/// A PNG of an RGB image of `size` pixels.
pub(super) fn png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, size.0, size.1);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header()?;
    w.write_image_data(rgb)?;
    w.finish()?;
    Ok(out)
}
