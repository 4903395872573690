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
//! abort.

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
    let mut bytes = read_prefix(path, limit.saturating_add(1))?;
    if bytes.len() as u64 > limit {
        bytes.clear();
        return Err(format!(
            "is larger than the limit of {} MiB",
            limit.div_ceil(1 << 20)
        ));
    }
    Ok(bytes)
}

/// Reads at most `max` bytes from the start of the regular file `path` (a file longer
/// than that is not an error: glTF buffers read only their declared length).
pub fn read_prefix(path: &Path, max: u64) -> Result<Vec<u8>, String> {
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
    let want = meta.len().min(max);
    let mut bytes = Vec::new();
    limits::try_reserve(&mut bytes, want as usize).map_err(|_| {
        format!(
            "needs {} MiB to be read, more memory than this process may use",
            want.div_ceil(1 << 20)
        )
    })?;
    file.take(max)
        .read_to_end(&mut bytes)
        .map_err(|e| io_reason(&e))?;
    Ok(bytes)
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
}
