//! The one way refract writes a file: to a temporary file beside the target, flushed and
//! checked, then moved into place, so a failed or interrupted write never leaves a partial
//! file under the final name (the temporary is removed on every error path).
//!
//! On Linux the temporary has no name while it is written (`O_TMPFILE`): a process killed
//! then (SIGTERM with no handler, SIGKILL, a crash) leaves nothing. When it is done it is
//! linked under the final name, or, to replace a file, under a temporary name renamed over
//! it at once. Where the file system has no unnamed files (or `/proc` is not mounted) the
//! temporary is a named `.NAME.XXXXXX.partial`, which a program's signal handler removes
//! ([`remove_temporaries`]).

use std::fmt::Display;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use refract_scene::SceneError;

/// The temporary files being written right now, for [`remove_temporaries`].
static LIVE_TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file a write in progress has open: what a program's SIGINT/SIGTERM
/// handler calls before exiting, so that an interrupted write leaves nothing behind (error paths
/// remove their temporaries themselves). Returns how many were removed.
pub fn remove_temporaries() -> usize {
    remove_temporaries_where(|_| true)
}

/// Removes the temporary files of writes in progress whose path `select` picks (those of one
/// experiment, say, while another thread's writes go on). Returns how many were removed.
pub fn remove_temporaries_where(select: impl Fn(&Path) -> bool) -> usize {
    live_temporaries()
        .iter()
        .filter(|path| select(path) && std::fs::remove_file(path).is_ok())
        .count()
}

/// The temporary files being written right now.
pub fn live_temporaries() -> Vec<PathBuf> {
    match LIVE_TEMPORARIES.lock() {
        Ok(live) => live.clone(),
        Err(poisoned) => poisoned.into_inner().clone(),
    }
}

/// Registers a temporary path for the lifetime of the guard.
struct LiveTemporary(PathBuf);

impl LiveTemporary {
    fn new(path: &Path) -> Self {
        if let Ok(mut live) = LIVE_TEMPORARIES.lock() {
            live.push(path.to_owned());
        }
        Self(path.to_owned())
    }
}

impl Drop for LiveTemporary {
    fn drop(&mut self) {
        if let Ok(mut live) = LIVE_TEMPORARIES.lock() {
            live.retain(|p| p != &self.0);
        }
    }
}

/// The longest file name most file systems take (`NAME_MAX`), in bytes.
const MAX_NAME_BYTES: usize = 255;
/// What the temporary's name adds to the final one: `.`, `.`, six random characters and
/// `.partial`.
const TEMPORARY_NAME_EXTRA: usize = 16;

/// The longest prefix of `text` of at most `max` bytes that ends on a character boundary.
fn truncate_at_char(text: &str, max: usize) -> &str {
    let mut end = text.len().min(max);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    &text[..end]
}

/// Writes `path` through `write`, atomically: `write` gets a buffered writer on a temporary
/// file in the same directory; the buffer is flushed (a failed flush is an error, e.g. a full
/// disk), then the file is renamed to `path`. `what` names the content in error messages.
pub fn write_atomically<E: Display>(
    path: &Path,
    what: &str,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> Result<(), E>,
) -> Result<(), SceneError> {
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let stem = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    // `.{stem}.XXXXXX.partial` is the name plus 16 bytes: a name near the 255-byte limit of
    // a file name keeps only its first bytes in the temporary's.
    let stem = truncate_at_char(&stem, MAX_NAME_BYTES - TEMPORARY_NAME_EXTRA);
    let prefix = format!(".{stem}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".partial");
    // The mode of the file written: an overwritten file keeps its own; a new one gets what the
    // umask gives (the OS applies it to 0666 at creation, as for any file a program creates),
    // not tempfile's private 0600.
    let existing = std::fs::metadata(path).ok().filter(|m| m.is_file());
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let create_error = |source| SceneError::Io {
        path: path.to_owned(),
        action: "cannot create a temporary file beside it",
        source,
    };
    let mut temporary = match unnamed::create(dir) {
        Some(file) => Temporary::Unnamed(file),
        None => Temporary::Named(builder.tempfile_in(dir).map_err(create_error)?),
    };
    let format = |message: String| SceneError::Format {
        path: path.to_owned(),
        message,
    };
    let _live = match &temporary {
        Temporary::Named(named) => Some(LiveTemporary::new(named.path())),
        Temporary::Unnamed(_) => None,
    };
    let file = match &mut temporary {
        Temporary::Named(named) => named.as_file_mut(),
        Temporary::Unnamed(file) => file,
    };
    {
        let mut writer = BufWriter::new(&mut *file);
        write(&mut writer).map_err(|err| format(format!("cannot write {what}: {err}")))?;
        writer
            .flush()
            .map_err(|err| format(format!("cannot write {what}: {err}")))?;
    }
    if let Some(existing) = existing {
        file.set_permissions(existing.permissions())
            .map_err(|source| SceneError::Io {
                path: path.to_owned(),
                action: "cannot give the new file the mode of the one it replaces",
                source,
            })?;
    }
    let moved = match temporary {
        Temporary::Named(named) => named.persist(path).map(drop).map_err(|err| err.error),
        Temporary::Unnamed(file) => unnamed::persist(&file, path, &builder, dir),
    };
    moved.map_err(|source| SceneError::Io {
        path: path.to_owned(),
        action: "cannot move the finished file into place",
        source,
    })
}

/// The file [`write_atomically`] writes before it is moved into place.
enum Temporary {
    /// A file with no name yet (Linux `O_TMPFILE`).
    Unnamed(File),
    /// `.NAME.XXXXXX.partial`, removed when dropped.
    Named(tempfile::NamedTempFile),
}

/// Files without a name until they are finished (Linux `O_TMPFILE`).
#[cfg(target_os = "linux")]
mod unnamed {
    use std::fs::File;
    use std::os::fd::AsRawFd;
    use std::path::Path;

    use rustix::fs::{AtFlags, CWD, Mode, OFlags};

    /// An unnamed file in `dir`, or `None` where the file system or the kernel has none.
    pub fn create(dir: &Path) -> Option<File> {
        // Without /proc the finished file could not be linked.
        if !Path::new("/proc/self/fd").is_dir() {
            return None;
        }
        let flags = OFlags::TMPFILE | OFlags::WRONLY | OFlags::CLOEXEC;
        // 0666: the umask applies, as for any file a program creates.
        rustix::fs::openat(CWD, dir, flags, Mode::from_raw_mode(0o666))
            .ok()
            .map(File::from)
    }

    /// Links the finished `file` as `path`: directly when `path` does not exist, else under a
    /// temporary name (made by `builder` in `dir`) renamed over `path`.
    pub fn persist(
        file: &File,
        path: &Path,
        builder: &tempfile::Builder<'_, '_>,
        dir: &Path,
    ) -> std::io::Result<()> {
        let source = format!("/proc/self/fd/{}", file.as_raw_fd());
        let link = |to: &Path| {
            rustix::fs::linkat(CWD, source.as_str(), CWD, to, AtFlags::SYMLINK_FOLLOW)
                .map_err(std::io::Error::from)
        };
        match link(path) {
            Err(err) if err.kind() == std::io::ErrorKind::AlreadyExists => {}
            linked => return linked,
        }
        let named = builder.make_in(dir, |name| link(name))?;
        named.persist(path).map(drop).map_err(|err| err.error)
    }
}

/// Elsewhere every temporary is named.
#[cfg(not(target_os = "linux"))]
mod unnamed {
    use std::fs::File;
    use std::path::Path;

    pub fn create(_dir: &Path) -> Option<File> {
        None
    }

    pub fn persist(
        _file: &File,
        _path: &Path,
        _builder: &tempfile::Builder<'_, '_>,
        _dir: &Path,
    ) -> std::io::Result<()> {
        unreachable!("no unnamed temporaries are created here")
    }
}

/// Checks, before a long computation, that [`write_atomically`] will be able to write `path`:
/// `path` is not a directory, and a temporary file can be created beside it (then removed).
/// The directory must exist.
pub fn check_writable(path: &Path) -> Result<(), SceneError> {
    if path.is_dir() {
        return Err(SceneError::Format {
            path: path.to_owned(),
            message: "is a directory; expected the name of a file to write".to_owned(),
        });
    }
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let probe = tempfile::Builder::new()
        .prefix(".refract-probe.")
        .suffix(".partial")
        .tempfile_in(dir)
        .map_err(|source| SceneError::Io {
            path: path.to_owned(),
            action: "cannot create a file beside it",
            source,
        })?;
    let _live = LiveTemporary::new(probe.path());
    drop(probe);
    Ok(())
}

/// [`write_atomically`] of a text.
pub fn write_text_atomically(path: &Path, text: &str) -> Result<(), SceneError> {
    write_atomically(path, "the text", |w| w.write_all(text.as_bytes()))
}

/// [`write_atomically`] of RGB8 pixels as a PNG.
pub fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[u8],
) -> Result<(), SceneError> {
    use image::ImageEncoder;
    write_atomically(path, "the PNG", |w| {
        image::codecs::png::PngEncoder::new(w).write_image(
            pixels,
            width,
            height,
            image::ExtendedColorType::Rgb8,
        )
    })
}

/// [`write_png_rgb8`] with `description`'s `(keyword, text)` pairs as the PNG's international
/// text chunks (`iTXt`, UTF-8; keywords of 1 to 79 Latin-1 characters), which image viewers
/// and `exiftool` show.
pub fn write_png_rgb8_described(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[u8],
    description: &[(&str, String)],
) -> Result<(), SceneError> {
    write_atomically(path, "the PNG", |w| -> Result<(), png::EncodingError> {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        for (keyword, text) in description {
            encoder.add_itxt_chunk((*keyword).to_owned(), text.clone())?;
        }
        encoder.write_header()?.write_image_data(pixels)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 54 #7: a name of up to 255 bytes is written (its temporary's name is cut to fit),
    /// multi-byte characters included, and nothing is left beside it.
    #[test]
    fn names_up_to_the_file_name_limit_are_written() {
        let dir = tempfile::tempdir().expect("tempdir");
        for name in ["a".repeat(255), format!("{}.txt", "é".repeat(125))] {
            assert!(name.len() <= 255);
            let path = dir.path().join(&name);
            write_text_atomically(&path, "x").unwrap_or_else(|e| panic!("{}: {e}", name.len()));
            assert_eq!(std::fs::read_to_string(&path).expect("read"), "x");
        }
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 2);
    }

    #[test]
    fn a_failed_write_leaves_no_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.txt");
        let result = write_atomically(&path, "the text", |_| Err("disk on fire"));
        assert!(result.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
        write_text_atomically(&path, "hello").expect("write");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "hello");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }

    /// A write in progress leaves nothing behind if the process dies there: on Linux it has no
    /// name in the directory (issue 54 #18: SIGTERM during a Python `Frame.save` left
    /// `.NAME.XXXXXX.partial`); elsewhere its named temporary is listed for signal handlers
    /// ([`remove_temporaries`]). Replacing a file works the same way. (Removing them here would
    /// race the other tests' writes.)
    #[test]
    fn a_write_in_progress_leaves_nothing_to_clean_up() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("slow.txt");
        let mine = |live: Vec<PathBuf>| {
            live.into_iter()
                .filter(|p| p.starts_with(dir.path()))
                .count()
        };
        let entries = || std::fs::read_dir(dir.path()).expect("dir").count();
        for (existing, text) in [(0, "first"), (1, "second")] {
            write_atomically(&path, "the text", |w| {
                w.write_all(b"half")?;
                if cfg!(target_os = "linux") {
                    assert_eq!(entries(), existing, "an entry for the file being written");
                    assert_eq!(mine(live_temporaries()), 0);
                } else {
                    assert_eq!(mine(live_temporaries()), 1);
                }
                w.write_all(text.as_bytes())
            })
            .expect("write");
            assert_eq!(mine(live_temporaries()), 0);
            assert_eq!(entries(), 1);
            assert_eq!(
                std::fs::read_to_string(&path).expect("read"),
                format!("half{text}")
            );
        }
    }

    #[test]
    fn renaming_onto_a_directory_fails_and_cleans_up() {
        let dir = tempfile::tempdir().expect("tempdir");
        let target = dir.path().join("taken");
        std::fs::create_dir(&target).expect("mkdir");
        assert!(write_text_atomically(&target, "x").is_err());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }

    /// A new file gets the mode the umask gives (that of a file `File::create` makes beside
    /// it), not 0600; an overwritten file keeps its mode (issue 34, item 2).
    #[cfg(unix)]
    #[test]
    fn files_get_the_umask_mode_and_keep_theirs() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("tempdir");
        let mode = |p: &Path| std::fs::metadata(p).expect("stat").permissions().mode() & 0o777;
        let plain = dir.path().join("plain.txt");
        std::fs::File::create(&plain).expect("create");
        let ours = dir.path().join("ours.txt");
        write_text_atomically(&ours, "x").expect("write");
        assert_eq!(mode(&ours), mode(&plain));
        assert_ne!(
            mode(&ours),
            0o600,
            "not tempfile's private mode (umask 077 aside)"
        );
        std::fs::set_permissions(&ours, std::fs::Permissions::from_mode(0o640)).expect("chmod");
        write_text_atomically(&ours, "y").expect("overwrite");
        assert_eq!(mode(&ours), 0o640);
        assert_eq!(std::fs::read_to_string(&ours).expect("read"), "y");
    }
}
