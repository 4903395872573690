//! Everything that writes files, below the commands that decide what to write.
//!
//! The files a command will write are checked before any work ([`check`], the one check
//! every command that writes uses): each has the extension of its documented format, no
//! two name the same file (through a symbolic or hard link too: an existing file is known
//! by its device and inode), none replaces an existing file without `--force`, none goes
//! through a dangling symbolic link, and each one's folder exists. A folder a command
//! fills with files it names as it goes (`render --dump`, `bench --plots`) must be new
//! or empty, or `--force` given. A report folder is recognised by a marker file only
//! shadowlab writes, and one holding a symbolic link is not taken for a report. Every
//! file is written whole through [`shadowlab::files::write_whole`] (a temporary file
//! renamed over the output), so a link left among the outputs is replaced, never written
//! through, and a failed write leaves no partial file. Then:
//! file names made from run labels ([`slug`]), pretty JSON ([`write_json`]), folders
//! ([`create_dir`]) and animated GIFs written frame by frame ([`Animation`]); PNG images
//! go through [`shadowlab::picture::save_png`]. A write that fails once the checks have passed is an internal failure
//! (exit status 1), not input.

use crate::failure::bad_input as bad;
use anyhow::{Context, Result};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{imageops, Delay, RgbImage};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// The file `compare` writes into its report folder, and only there: a folder holding it
/// is an earlier report, which may be written over without `--force`.
pub const REPORT_MARKER: &str = ".shadowlab-report";

/// What the marker file says.
const REPORT_MARKER_TEXT: &str =
    "This folder is a shadowlab report; `shadowlab compare --out` may replace its files.\n";

/// One file a command is about to write.
pub struct Planned {
    /// The file.
    pub path: PathBuf,
    /// The flag (or flag and role) that names it, for messages.
    pub flag: String,
    /// The extensions its format allows (lower case, without the dot); empty: any.
    pub extensions: &'static [&'static str],
    /// A folder the command fills, rather than a file.
    pub folder: bool,
}

impl Planned {
    /// A file named by `flag` that must end in one of `extensions`.
    pub fn new(path: &Path, flag: impl Into<String>, extensions: &'static [&'static str]) -> Self {
        Planned {
            path: path.to_path_buf(),
            flag: flag.into(),
            extensions,
            folder: false,
        }
    }

    /// A folder named by `flag` that the command fills with files of its own naming.
    pub fn folder(path: &Path, flag: impl Into<String>) -> Self {
        Planned {
            folder: true,
            ..Planned::new(path, flag, &[])
        }
    }
}

/// What two spellings of one file share: an existing file's device and inode (the same
/// through symbolic and hard links), else the absolute path with its folder made
/// canonical (it exists, or the check fails first) and its name kept.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Identity {
    Existing(u64, u64),
    New(PathBuf),
}

fn identity(path: &Path) -> Identity {
    use std::os::unix::fs::MetadataExt;
    if let Ok(m) = std::fs::metadata(path) {
        return Identity::Existing(m.dev(), m.ino());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let dir = std::fs::canonicalize(parent).unwrap_or_else(|_| parent.to_path_buf());
    Identity::New(match path.file_name() {
        Some(n) => dir.join(n),
        None => dir,
    })
}

/// Checks every planned file (see the module doc); `force` allows replacing existing
/// regular files, never folders or dangling links.
pub fn check(planned: &[Planned], force: bool) -> Result<()> {
    let mut seen: BTreeMap<Identity, &str> = BTreeMap::new();
    for p in planned {
        let shown = p.path.display();
        if !p.extensions.is_empty() {
            let ext = p
                .path
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase());
            if !ext.is_some_and(|e| p.extensions.contains(&e.as_str())) {
                let want: Vec<String> = p.extensions.iter().map(|e| format!(".{e}")).collect();
                return Err(bad(format!(
                    "{} {shown} must end in {} (the format it writes)",
                    p.flag,
                    want.join(" or ")
                )));
            }
        }
        if p.folder {
            check_folder(&p.path, &p.flag, force)?;
        } else {
            check_one(&p.path, &p.flag, force)?;
        }
        if let Some(other) = seen.insert(identity(&p.path), &p.flag) {
            return Err(bad(format!(
                "{} and {} both name the file {shown}; give each output its own file",
                other, p.flag
            )));
        }
    }
    Ok(())
}

/// One file: its folder exists, and it is new, or an existing regular file with `force`.
fn check_one(path: &Path, flag: &str, force: bool) -> Result<()> {
    let shown = path.display();
    if let Ok(link) = std::fs::symlink_metadata(path) {
        if link.file_type().is_symlink() && std::fs::metadata(path).is_err() {
            return Err(bad(format!(
                "{flag} {shown} is a symbolic link to a file that does not exist; remove the link or name another file"
            )));
        }
        let meta = std::fs::metadata(path).unwrap_or(link);
        if !meta.is_file() {
            let kind = shadowlab::files::special_kind(&meta.file_type()).unwrap_or("not a file");
            return Err(bad(format!(
                "{flag} {shown} is {kind}, not a file that can be written"
            )));
        }
        if !force {
            return Err(bad(format!(
                "{flag} {shown} already exists; pass --force to overwrite it"
            )));
        }
        return Ok(());
    }
    parent_exists(path, flag)
}

/// A folder the command fills: new (its parent exists), or an existing folder that is
/// empty or, with `force`, holds files the command may replace.
fn check_folder(dir: &Path, flag: &str, force: bool) -> Result<()> {
    let shown = dir.display();
    if std::fs::symlink_metadata(dir).is_err() {
        return parent_exists(dir, flag);
    }
    let Ok(meta) = std::fs::metadata(dir) else {
        return Err(bad(format!(
            "{flag} {shown} is a symbolic link to a folder that does not exist"
        )));
    };
    if !meta.is_dir() {
        return Err(bad(format!("{flag} {shown} exists and is not a folder")));
    }
    let non_empty = std::fs::read_dir(dir)
        .map_err(|e| {
            bad(format!(
                "{flag} {shown} {}",
                shadowlab::files::io_reason(&e)
            ))
        })?
        .next()
        .is_some();
    if non_empty && !force {
        return Err(bad(format!(
            "{flag} {shown} is a folder that already holds files, which this run may replace; pass --force to write into it"
        )));
    }
    Ok(())
}

/// The folder that will hold `path` exists.
fn parent_exists(path: &Path, flag: &str) -> Result<()> {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(bad(format!(
            "{flag} {}: the folder {} does not exist",
            path.display(),
            parent.display()
        )));
    }
    Ok(())
}

/// Checks a report folder before any work: it may be new, empty, or an earlier report
/// (it holds [`REPORT_MARKER`]); anything else needs `force`. Creates nothing.
pub fn check_report_dir(dir: &Path, force: bool) -> Result<()> {
    let shown = dir.display();
    if let Ok(link) = std::fs::symlink_metadata(dir) {
        let Ok(meta) = std::fs::metadata(dir) else {
            return Err(bad(format!(
                "--out {shown} is a symbolic link to a folder that does not exist"
            )));
        };
        if !meta.is_dir() {
            let _ = link;
            return Err(bad(format!("--out {shown} exists and is not a folder")));
        }
        let non_empty = std::fs::read_dir(dir)
            .map_err(|e| bad(format!("--out {shown} {}", shadowlab::files::io_reason(&e))))?
            .next()
            .is_some();
        let is_report = std::fs::symlink_metadata(dir.join(REPORT_MARKER))
            .is_ok_and(|m| m.file_type().is_file());
        if non_empty && !is_report && !force {
            return Err(bad(format!(
                "--out {shown} is a non-empty folder that is not a shadowlab report; pass --force to write into it"
            )));
        }
        if let (Some(link), false) = (first_link(dir), force) {
            return Err(bad(format!(
                "--out {shown} holds {}, a symbolic link, which shadowlab never writes in a report; pass --force to replace it",
                link.display()
            )));
        }
    } else {
        parent_exists(dir, "--out")?;
    }
    Ok(())
}

/// The first symbolic link in `dir` or in the folders below it that a report makes.
fn first_link(dir: &Path) -> Option<PathBuf> {
    let mut folders = vec![dir.to_path_buf()];
    while let Some(d) = folders.pop() {
        for entry in std::fs::read_dir(&d).ok()?.flatten() {
            let Ok(ft) = entry.file_type() else { continue };
            if ft.is_symlink() {
                return Some(entry.path());
            }
            if ft.is_dir() && folders.len() < 64 {
                folders.push(entry.path());
            }
        }
    }
    None
}

/// Creates the report folder (checked by [`check_report_dir`]) with its marker.
pub fn create_report_dir(dir: &Path) -> Result<()> {
    create_dir(dir)?;
    write_file(&dir.join(REPORT_MARKER), REPORT_MARKER_TEXT.as_bytes())
}

/// Writes `bytes` to `path` whole or not at all ([`shadowlab::files::write_whole`]).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    shadowlab::files::write_whole(path, bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Creates a folder and its parents.
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))
}

/// The file of frame `i` of a sequence written beside `output`: `OUT-NNNN.png`.
pub fn frame_file(output: &Path, i: usize) -> PathBuf {
    let stem = output.with_extension("");
    PathBuf::from(format!("{}-{i:04}.png", stem.display()))
}

/// File-name-safe form of a run label.
pub fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes `v` as pretty JSON with a final newline.
pub fn write_json(path: &Path, v: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(v)
        .with_context(|| format!("cannot write {}", path.display()))?;
    write_file(path, (text + "\n").as_bytes())
}

/// Display time of one animation frame in milliseconds (10 frames per second).
pub const ANIMATION_FRAME_MS: u32 = 100;
/// Animations are scaled down to at most this width: GIF size grows with the pixel count
/// and its 256-colour palette hides fine detail anyway; the numbered PNGs keep full size.
pub const ANIMATION_MAX_WIDTH: u32 = 640;
/// GIF palette quantization speed (1 = best colours, 30 = fastest): 10 keeps shadow
/// gradients without banding at a few tens of milliseconds per frame.
const ANIMATION_QUANTIZE_SPEED: i32 = 10;

/// Side-by-side animations (two panels) are scaled down to at most this width.
pub const ANIMATION_PAIR_MAX_WIDTH: u32 = 960;
/// White columns between the panels of a side-by-side animation frame.
const PAIR_GAP: u32 = 8;

/// Writes an animated GIF frame by frame, so a walkthrough never sits in memory: into a
/// temporary file beside it, renamed over it by [`Animation::finish`] (dropped unfinished,
/// the temporary file is removed).
pub struct Animation {
    encoder: Option<GifEncoder<BufWriter<File>>>,
    path: PathBuf,
    partial: PathBuf,
    max_width: u32,
}

impl Drop for Animation {
    fn drop(&mut self) {
        if self.encoder.take().is_some() {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

impl Animation {
    /// Starts an endlessly looping animation at `path`, its frames scaled down to
    /// [`ANIMATION_MAX_WIDTH`].
    pub fn create(path: &Path) -> Result<Self> {
        Self::create_with_width(path, ANIMATION_MAX_WIDTH)
    }

    /// Starts an endlessly looping animation of two panels side by side (see
    /// [`Animation::push_pair`]), scaled down to [`ANIMATION_PAIR_MAX_WIDTH`].
    pub fn create_pair(path: &Path) -> Result<Self> {
        Self::create_with_width(path, ANIMATION_PAIR_MAX_WIDTH)
    }

    fn create_with_width(path: &Path, max_width: u32) -> Result<Self> {
        let mut name = std::ffi::OsString::from(".");
        name.push(path.file_name().unwrap_or_default());
        name.push(format!(".{}.partial", std::process::id()));
        let partial = path.with_file_name(name);
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&partial)
            .with_context(|| format!("cannot create {}", path.display()))?;
        let encoder = GifEncoder::new_with_speed(BufWriter::new(file), ANIMATION_QUANTIZE_SPEED);
        let mut anim = Animation {
            encoder: Some(encoder),
            path: path.to_path_buf(),
            partial,
            max_width,
        };
        anim.encoder()?
            .set_repeat(Repeat::Infinite)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(anim)
    }

    fn encoder(&mut self) -> Result<&mut GifEncoder<BufWriter<File>>> {
        let shown = self.path.display().to_string();
        self.encoder
            .as_mut()
            .with_context(|| format!("cannot write {shown}: already finished"))
    }

    /// Appends one frame of two images of one size side by side, `left` and `right`, with
    /// a white gap between them.
    pub fn push_pair(&mut self, left: &RgbImage, right: &RgbImage) -> Result<()> {
        let (w, h) = left.dimensions();
        let mut both = RgbImage::from_pixel(2 * w + PAIR_GAP, h, image::Rgb([255, 255, 255]));
        imageops::replace(&mut both, left, 0, 0);
        imageops::replace(&mut both, right, i64::from(w + PAIR_GAP), 0);
        self.push(&both)
    }

    /// Appends one frame, scaled down to the animation's largest width if wider.
    pub fn push(&mut self, img: &RgbImage) -> Result<()> {
        let max = self.max_width;
        let rgba = if img.width() > max {
            let h = ((img.height() as u64 * max as u64) / img.width() as u64).max(1) as u32;
            image::DynamicImage::ImageRgb8(imageops::resize(
                img,
                max,
                h,
                imageops::FilterType::Triangle,
            ))
            .into_rgba8()
        } else {
            image::DynamicImage::ImageRgb8(img.clone()).into_rgba8()
        };
        let frame = image::Frame::from_parts(
            rgba,
            0,
            0,
            Delay::from_numer_denom_ms(ANIMATION_FRAME_MS, 1),
        );
        let shown = self.path.display().to_string();
        self.encoder()?
            .encode_frame(frame)
            .with_context(|| format!("cannot write {shown}"))
    }

    /// Finishes the file and puts it in place.
    pub fn finish(mut self) -> Result<()> {
        // The GIF trailer is written when the encoder drops; the buffer flushes with it.
        drop(self.encoder.take());
        let renamed = std::fs::rename(&self.partial, &self.path);
        if renamed.is_err() {
            let _ = std::fs::remove_file(&self.partial);
        }
        renamed.with_context(|| format!("cannot write {}", self.path.display()))
    }
}
