//! Reading the user's files: only regular files are read, never more than a declared
//! length or a size limit allows, and files a scene refers to (glTF buffers, OBJ material
//! libraries, the meshes of a TOML scene) resolve inside the scene's folder unless the
//! caller allows more.
//!
//! Every loader and every referenced file goes through [`read_regular_file`]: it opens
//! without blocking (a FIFO with no writer would otherwise wait forever), looks at what
//! the opened file is, refuses FIFOs, devices, sockets and folders by name, and reads at
//! most the limit into a buffer reserved fallibly, so `/dev/zero`, a 3 GB file behind a
//! 44-byte buffer or a short address-space limit end in a sentence, not in a hang or an
//! abort. A loader's own file goes through [`read_sniffed`], which shows the format check
//! the first bytes before reading (or reserving room for) the rest.
//!
//! Every file shadowlab writes goes through [`write_whole`]: a temporary file beside it,
//! renamed over it once complete, so a failed write leaves nothing behind and a link is
//! replaced rather than written through.

use crate::limits;
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};

/// The largest file a mesh loader or a glTF buffer reads (4 GiB): more than any scene
/// that fits in memory with its acceleration structure.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// The largest TOML scene file (16 MiB). A scene file places meshes and key frames; its
/// geometry lives in the files it names, so anything larger is not a scene.
pub const MAX_SCENE_TEXT_BYTES: u64 = 16 << 20;

/// What a path is, in words, when it is not a regular file (`None` for a regular file).
pub fn special_kind(ft: &std::fs::FileType) -> Option<&'static str> {
    if ft.is_file() {
        None
    } else if ft.is_dir() {
        Some("a folder")
    } else if ft.is_fifo() {
        Some("a FIFO (named pipe)")
    } else if ft.is_char_device() {
        Some("a character device")
    } else if ft.is_block_device() {
        Some("a block device")
    } else if ft.is_socket() {
        Some("a socket")
    } else {
        Some("not a regular file")
    }
}

/// Why a path cannot be read, in a few words, without repeating the path: "does not
/// exist", "is a FIFO (named pipe), not a regular file", …
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "does not exist".into(),
        std::io::ErrorKind::PermissionDenied => "cannot be read (permission denied)".into(),
        _ => {
            // The OS message without its "(os error N)" suffix.
            let s = e.to_string();
            match s.find(" (os error") {
                Some(i) => format!("cannot be read ({})", &s[..i].to_lowercase()),
                None => format!("cannot be read ({s})"),
            }
        }
    }
}

/// Reads the regular file `path`, refusing anything else (FIFO, device, socket, folder)
/// at once and refusing a file longer than `limit` bytes; `Err` is a phrase that
/// completes "`path` …", e.g. "is a FIFO (named pipe), not a regular file".
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let bytes = read_prefix(path, limit.saturating_add(1))?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// Reads at most `max` bytes from the start of the regular file `path` (a file longer
/// than that is not an error: glTF buffers read only their declared length).
pub fn read_prefix(path: &Path, max: u64) -> Result<Vec<u8>, String> {
    let (file, len) = open_regular(path)?;
    let mut bytes = reserve(len.min(max))?;
    file.take(max)
        .read_to_end(&mut bytes)
        .map_err(|e| io_reason(&e))?;
    Ok(bytes)
}

/// Bytes a loader's format check sees before the rest of a file is read (64 KiB): enough
/// for a PLY header's first lines, a GLB header or the opening of a JSON document.
pub const SNIFF_BYTES: u64 = 64 << 10;

/// Why [`read_sniffed`] read no file: the file itself (a phrase for "`path` …", as
/// [`read_regular_file`] gives), or its first bytes are not the format expected (the
/// format check's phrase).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Unread {
    /// Not a regular file, missing, unreadable, over the limit or over the memory limit.
    File(String),
    /// The format check refused the first [`SNIFF_BYTES`].
    Format(String),
}

/// Reads the regular file `path` of at most `limit` bytes, as [`read_regular_file`] does,
/// after handing its first [`SNIFF_BYTES`] to `sniff`: a file whose start is not the
/// expected format (a 3 GB file of NUL bytes named `.ply`) is refused before the rest is
/// read or any room is reserved for it.
pub fn read_sniffed(
    path: &Path,
    limit: u64,
    sniff: impl FnOnce(&[u8]) -> Result<(), String>,
) -> Result<Vec<u8>, Unread> {
    let (mut file, len) = open_regular(path).map_err(Unread::File)?;
    let mut head = Vec::new();
    (&mut file)
        .take(SNIFF_BYTES.min(limit.saturating_add(1)))
        .read_to_end(&mut head)
        .map_err(|e| Unread::File(io_reason(&e)))?;
    sniff(&head).map_err(Unread::Format)?;
    if len > limit {
        return Err(Unread::File(too_large(limit)));
    }
    let mut bytes = reserve(len.max(head.len() as u64)).map_err(Unread::File)?;
    bytes.extend_from_slice(&head);
    let rest = limit.saturating_add(1).saturating_sub(head.len() as u64);
    file.take(rest)
        .read_to_end(&mut bytes)
        .map_err(|e| Unread::File(io_reason(&e)))?;
    if bytes.len() as u64 > limit {
        return Err(Unread::File(too_large(limit)));
    }
    Ok(bytes)
}

/// A format check for text formats (OBJ, TOML, material libraries): the first bytes
/// hold no NUL byte; `format` names the format ("an OBJ file").
pub fn sniff_text(head: &[u8], format: &str) -> Result<(), String> {
    match head.iter().position(|&b| b == 0) {
        Some(i) => Err(format!(
            "it is not {format}: byte {i} is a NUL byte, and the format is text"
        )),
        None => Ok(()),
    }
}

fn too_large(limit: u64) -> String {
    format!(
        "is larger than the limit of {} MiB",
        limit.div_ceil(1 << 20)
    )
}

/// Opens the regular file `path` for reading, refusing anything else at once; returns
/// the file and its length.
fn open_regular(path: &Path) -> Result<(std::fs::File, u64), String> {
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer. It has
    // no effect on regular files, which are the only ones read.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(|e| match std::fs::metadata(path) {
            Ok(m) if special_kind(&m.file_type()).is_some() => {
                not_regular(special_kind(&m.file_type()).unwrap_or_default())
            }
            _ => io_reason(&e),
        })?;
    let meta = file.metadata().map_err(|e| io_reason(&e))?;
    if let Some(kind) = special_kind(&meta.file_type()) {
        return Err(not_regular(kind));
    }
    Ok((file, meta.len()))
}

/// An empty buffer with room for `want` bytes, reserved fallibly.
fn reserve(want: u64) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    limits::try_reserve(&mut bytes, want as usize).map_err(|_| {
        format!(
            "needs {} MiB to be read, more memory than this process may use",
            want.div_ceil(1 << 20)
        )
    })?;
    Ok(bytes)
}

/// Writes `bytes` to `path` whole or not at all: into a new temporary file in the same
/// folder, then renamed over `path`. A failed write (a full disk, a file-size limit)
/// leaves no partial file and the old one untouched, and a `path` that is a link is
/// replaced, never written through (the file it points to is not the output's).
pub fn write_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let name = path.file_name().ok_or_else(|| {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file")
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.partial", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.flush()));
    let renamed = written.and_then(|()| std::fs::rename(&tmp, path));
    if renamed.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    renamed
}

fn not_regular(kind: &str) -> String {
    if kind == "not a regular file" {
        "is not a regular file".into()
    } else {
        format!("is {kind}, not a regular file")
    }
}

/// Where the files a scene refers to may be: inside the folder of the scene file (the
/// default), or anywhere.
#[derive(Clone, Debug, Default)]
pub struct Access {
    /// The folder references must stay in, canonical; `None` allows any path.
    root: Option<PathBuf>,
}

impl Access {
    /// References may name any file.
    pub fn anywhere() -> Self {
        Access { root: None }
    }

    /// References must stay inside the folder holding `scene_file`; with
    /// `allow_outside`, anywhere.
    pub fn for_scene(scene_file: &Path, allow_outside: bool) -> Self {
        if allow_outside {
            return Access::anywhere();
        }
        let folder = match scene_file.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        // An unreadable folder keeps the lexical path, so every reference is refused
        // rather than allowed.
        let root = std::fs::canonicalize(folder).unwrap_or_else(|_| folder.to_path_buf());
        Access { root: Some(root) }
    }

    /// True when references may leave the scene's folder.
    pub fn is_unrestricted(&self) -> bool {
        self.root.is_none()
    }

    /// The file that `reference` (as written in the scene, already percent-decoded)
    /// names, relative to `base` (the folder of the file that holds it). `Err` is a
    /// phrase naming why it is refused: outside the scene's folder, or missing.
    pub fn resolve(&self, base: &Path, reference: &str) -> Result<PathBuf, String> {
        let full = base.join(reference);
        let Some(root) = &self.root else {
            return Ok(full);
        };
        let outside = || {
            format!(
                "is outside the scene's folder {} (pass --allow-outside-scene-dir to read it)",
                root.display()
            )
        };
        // Links inside the folder may still point out of it: the canonical path decides.
        match std::fs::canonicalize(&full) {
            Ok(c) if c.starts_with(root) => Ok(full),
            Ok(_) => Err(outside()),
            // A missing file is outside when its path, taken literally, leaves the folder.
            Err(e) => {
                let base = std::fs::canonicalize(base).unwrap_or_else(|_| base.to_path_buf());
                let mut lexical = PathBuf::new();
                for c in base.join(reference).components() {
                    match c {
                        Component::ParentDir => {
                            lexical.pop();
                        }
                        Component::CurDir => {}
                        other => lexical.push(other),
                    }
                }
                if lexical.starts_with(root) {
                    Err(io_reason(&e))
                } else {
                    Err(outside())
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_stay_inside_the_scene_folder() {
        let dir = std::env::temp_dir().join(format!("shadowlab-files-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("sub/a.bin"), b"abc").unwrap();
        let access = Access::for_scene(&dir.join("scene.gltf"), false);
        assert!(access.resolve(&dir, "sub/a.bin").is_ok());
        for bad in ["../x.bin", "/etc/passwd", "sub/../../x"] {
            let e = access.resolve(&dir, bad).unwrap_err();
            assert!(e.contains("outside the scene's folder"), "{bad}: {e}");
        }
        assert_eq!(
            access.resolve(&dir, "missing.bin").unwrap_err(),
            "does not exist"
        );
        assert!(Access::anywhere().resolve(&dir, "../x").is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn only_regular_files_are_read_and_never_past_the_limit() {
        let e = read_regular_file(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e, "is a character device, not a regular file");
        let e = read_regular_file(Path::new("/"), 1 << 20).unwrap_err();
        assert_eq!(e, "is a folder, not a regular file");
        let dir = std::env::temp_dir().join(format!("shadowlab-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("ten.bin");
        std::fs::write(&f, [7u8; 10]).unwrap();
        assert_eq!(read_regular_file(&f, 10).unwrap().len(), 10);
        assert!(read_regular_file(&f, 9)
            .unwrap_err()
            .contains("larger than"));
        assert_eq!(read_prefix(&f, 4).unwrap(), vec![7u8; 4]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_format_check_sees_the_first_bytes_before_the_rest_is_read() {
        let dir = std::env::temp_dir().join(format!("shadowlab-sniff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let zeros = dir.join("zeros.obj");
        // 3 GiB of zeros that take no disk; read whole they would take 3 GiB of memory.
        std::fs::File::create(&zeros)
            .unwrap()
            .set_len(3 << 30)
            .unwrap();
        let seen = std::cell::Cell::new(0);
        let e = read_sniffed(&zeros, MAX_FILE_BYTES, |h| {
            seen.set(h.len());
            sniff_text(h, "an OBJ file")
        })
        .unwrap_err();
        assert_eq!(seen.get() as u64, SNIFF_BYTES);
        assert_eq!(
            e,
            Unread::Format(
                "it is not an OBJ file: byte 0 is a NUL byte, and the format is text".into()
            )
        );
        // A file the check accepts is read whole, the first bytes included once.
        let text = dir.join("tri.obj");
        let body = "v 0 0 0\n".repeat(20_000);
        std::fs::write(&text, &body).unwrap();
        let read = read_sniffed(&text, MAX_FILE_BYTES, |h| sniff_text(h, "an OBJ file")).unwrap();
        assert_eq!(read, body.as_bytes());
        assert_eq!(
            read_sniffed(&text, 10, |_| Ok(())).unwrap_err(),
            Unread::File("is larger than the limit of 1 MiB".into())
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn writes_are_whole_and_replace_links_instead_of_following_them() {
        let dir = std::env::temp_dir().join(format!("shadowlab-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("theirs.txt");
        std::fs::write(&target, "theirs").unwrap();
        let link = dir.join("out.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_whole(&link, b"ours").unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "theirs");
        assert_eq!(std::fs::read_to_string(&link).unwrap(), "ours");
        assert!(std::fs::symlink_metadata(&link).unwrap().is_file());
        // A write that fails leaves nothing behind.
        assert!(write_whole(&dir.join("missing/out.txt"), b"x").is_err());
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(names.len(), 2, "{names:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
