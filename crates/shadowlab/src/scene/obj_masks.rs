//! OBJ alpha cut-outs: the textures of an `.mtl` material that cut its triangles out, read
//! with the same semantics as a glTF `MASK` material (see [`super::alpha_mask`]): nearest
//! texel, cut-off 0.5, coordinates outside `[0, 1)` repeating (clamped to the edge with the
//! statement's `-clamp on`).
//!
//! - `map_d`: its alpha channel, or its grey level when it has no alpha (a grey mask).
//!   Refused, naming the material and the image, when it cannot be read or decoded, is
//!   larger than glTF's textures may be, or lies outside the scene's folder; a `map_d` that
//!   does not exist leaves the material whole, said in a warning.
//! - otherwise the alpha channel of `map_Kd`, when that image has one and the loader is
//!   asked to (on by default): not every program reads `map_Kd` so, so one warning per file
//!   names the materials it cut out. An image without alpha (every JPEG) cuts nothing; one
//!   that cannot be read leaves the material whole, said in a warning, as a glTF texture.
//!
//! The images are read through the scene loaders' shared decoder ([`TextureCache`]), within
//! its limits, each once per file however many materials share it. `d` and `Tr` stay the uniform transmittance they
//! are without a texture.

use super::alpha_mask::{AlphaMask, AlphaTexture, Wrap};
use super::texture_cache::{Channel, TextureCache};
use crate::error::{Error, Result};
use crate::files::{read_regular_file, Access, MAX_FILE_BYTES};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A texture statement's image and the options shadowlab reads from it.
#[derive(Debug, PartialEq)]
struct TextureRef {
    /// The image's file name as written (backslashes turned into slashes).
    file: String,
    /// `-clamp on`: coordinates outside `[0, 1)` clamp to the edge texels.
    clamp: bool,
    /// The options present but not read (`-o`, `-s`, `-imfchan`, …).
    ignored: Vec<String>,
}

/// Splits a texture statement's argument (`-clamp on -bm 0.2 leaf.png`) into its options
/// and the image's name.
fn parse_texture(arg: &str) -> TextureRef {
    let tokens: Vec<&str> = arg.split_whitespace().collect();
    let (mut i, mut clamp, mut ignored) = (0, false, Vec::new());
    while i + 1 < tokens.len() && tokens[i].starts_with('-') {
        let option = tokens[i];
        let args = match option {
            "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-clamp" | "-imfchan"
            | "-texres" | "-type" => 1,
            "-mm" => 2,
            // One to three numbers.
            "-o" | "-s" | "-t" => tokens[i + 1..]
                .iter()
                .take(3)
                .take_while(|t| t.parse::<f32>().is_ok())
                .count(),
            _ => break,
        };
        if option == "-clamp" {
            clamp = tokens[i + 1].eq_ignore_ascii_case("on");
        } else {
            ignored.push(option.to_string());
        }
        i = (i + 1 + args).min(tokens.len() - 1);
    }
    TextureRef {
        file: tokens[i.min(tokens.len().saturating_sub(1))..]
            .join(" ")
            .replace('\\', "/"),
        clamp,
        ignored,
    }
}

/// A decoded image (or `None`: no alpha to cut with) or why it could not be read.
type Read = std::result::Result<Option<Arc<AlphaTexture>>, String>;

/// Reads the cut-outs of one OBJ file's materials, and what to warn about them.
pub(super) struct Masks<'a> {
    /// The OBJ file, named in errors and warnings.
    path: &'a Path,
    access: &'a Access,
    /// Whether `map_Kd` alpha cuts materials without `map_d` out.
    kd_alpha: bool,
    /// Decoded images by file and whether a grey image is read as alpha.
    cache: BTreeMap<(PathBuf, bool), Read>,
    /// The decoder: each distinct image decoded once, their sum within the memory limit.
    textures: TextureCache,
    /// Materials cut out by their `map_Kd` alpha.
    kd_cut: Vec<String>,
    /// Warnings, one per material and image that could not be used.
    notes: Vec<String>,
    /// Texture options present but not read.
    ignored: BTreeSet<String>,
}

impl<'a> Masks<'a> {
    /// The reader for the OBJ file `path`, its images resolved as `access` allows.
    pub(super) fn new(path: &'a Path, access: &'a Access, kd_alpha: bool) -> Self {
        Masks {
            path,
            access,
            kd_alpha,
            cache: BTreeMap::new(),
            textures: TextureCache::default(),
            kd_cut: Vec::new(),
            notes: Vec::new(),
            ignored: BTreeSet::new(),
        }
    }

    /// The cut-out of material `m`, whose library lies in the folder `dir`; `None` when it
    /// has none (or it cannot be read and is not `map_d`'s).
    pub(super) fn mask(&mut self, m: &tobj::Material, dir: &Path) -> Result<Option<AlphaMask>> {
        if let Some(d) = &m.dissolve_texture {
            let t = parse_texture(d);
            return match self.read(dir, &t.file, true) {
                Ok(Some(texture)) => Ok(Some(self.made(texture, &t))),
                Ok(None) => Ok(None),
                Err(why) if why == "does not exist" => {
                    self.notes.push(format!(
                        "material {:?}: its map_d {:?} does not exist, so it is not cut out",
                        m.name, t.file
                    ));
                    Ok(None)
                }
                Err(why) => Err(Error::format(
                    self.path,
                    format!(
                        "material {:?}: its map_d image {:?} cannot be used: {why}",
                        m.name, t.file
                    ),
                )),
            };
        }
        let Some(kd) = m.diffuse_texture.as_ref().filter(|_| self.kd_alpha) else {
            return Ok(None);
        };
        let t = parse_texture(kd);
        match self.read(dir, &t.file, false) {
            Ok(Some(texture)) => {
                self.kd_cut.push(m.name.clone());
                Ok(Some(self.made(texture, &t)))
            }
            Ok(None) => Ok(None),
            Err(why) if why == "does not exist" => Ok(None),
            Err(why) => {
                self.notes.push(format!(
                    "material {:?}: its map_Kd image {:?} cannot be used ({why}), so its alpha does not cut it out",
                    m.name, t.file
                ));
                Ok(None)
            }
        }
    }

    /// The mask of texture statement `t` with image `texture`.
    fn made(&mut self, texture: Arc<AlphaTexture>, t: &TextureRef) -> AlphaMask {
        self.ignored.extend(t.ignored.iter().cloned());
        let wrap = if t.clamp {
            Wrap::ClampToEdge
        } else {
            Wrap::Repeat
        };
        AlphaMask {
            texture,
            factor: 1.0,
            cutoff: 0.5,
            wrap_u: wrap,
            wrap_v: wrap,
        }
    }

    /// The image `file` beside the library in `dir`: its alpha, or with `grey` its grey
    /// level when it has no alpha; `None` without `grey` for an image without alpha. `Err`
    /// is a clause saying why it cannot be used, or just "does not exist".
    fn read(&mut self, dir: &Path, file: &str, grey: bool) -> Read {
        let full = match self.access.resolve(dir, file) {
            Ok(f) => f,
            Err(why) if why == "does not exist" => return Err(why),
            Err(why) => return Err(format!("it {why}")),
        };
        let key = (full.clone(), grey);
        if let Some(r) = self.cache.get(&key) {
            return r.clone();
        }
        let channel = if grey {
            Channel::AlphaOrGrey
        } else {
            Channel::AlphaOnly
        };
        let r = read_regular_file(&full, MAX_FILE_BYTES)
            .map_err(|why| {
                if why == "does not exist" {
                    why
                } else {
                    format!("the file {} {why}", full.display())
                }
            })
            .and_then(|bytes| self.textures.channel(&bytes, channel));
        self.cache.insert(key, r.clone());
        r
    }

    /// What to warn about, one sentence per kind, naming the file.
    pub(super) fn warnings(self) -> Vec<String> {
        let name = super::file_name(self.path);
        let mut out: Vec<String> = self
            .notes
            .into_iter()
            .map(|n| format!("{name}: {n}"))
            .collect();
        if !self.kd_cut.is_empty() {
            let n = self.kd_cut.len();
            let shown: Vec<String> = self
                .kd_cut
                .iter()
                .take(8)
                .map(|m| format!("{m:?}"))
                .collect();
            out.push(format!(
                "{name}: {n} material{} without map_d cut out by the alpha channel of {} map_Kd image ({}{}); not every program reads map_Kd so (--obj-kd-alpha false keeps them whole)",
                if n == 1 { "" } else { "s" },
                if n == 1 { "its" } else { "their" },
                shown.join(", "),
                if n > 8 { ", …" } else { "" }
            ));
        }
        if !self.ignored.is_empty() {
            let list: Vec<&str> = self.ignored.iter().map(String::as_str).collect();
            out.push(format!(
                "{name}: texture options {} are not read: the cut-outs take their images as they are",
                list.join(", ")
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_statements_split_into_options_and_the_file() {
        let t = parse_texture("leaf.png");
        assert_eq!((t.file.as_str(), t.clamp), ("leaf.png", false));
        let t = parse_texture("-clamp on -s 2 2 1 -bm 0.5 textures\\my leaf.png");
        assert_eq!(t.file, "textures/my leaf.png");
        assert!(t.clamp);
        assert_eq!(t.ignored, ["-s", "-bm"]);
        let t = parse_texture("-o 0.5 -clamp off a.png");
        assert_eq!((t.file.as_str(), t.clamp), ("a.png", false));
        // A name that starts with a dash but is no option, and an option with no file.
        assert_eq!(parse_texture("-leaf.png").file, "-leaf.png");
        assert_eq!(parse_texture("-clamp on").file, "on");
    }
}
