//! The report's gallery of intermediate images: whatever the techniques dumped into
//! `DIR/dump` (shadow maps, warped maps, sample points, tile trees, masks), grouped by
//! technique, with the files that are not images listed by name.

use super::format::{esc, url};
use std::fmt::Write as _;
use std::path::Path;

/// At most this many dumped images are shown in the gallery; the rest are listed by count.
pub const DUMP_GALLERY_MAX: usize = 240;

/// What a report's dump folder holds, relative to the report folder and sorted.
pub struct Dumped {
    /// Images (PNG, JPEG, GIF, SVG).
    pub images: Vec<String>,
    /// Everything else.
    pub other: Vec<String>,
}

impl Dumped {
    /// The files under `DIR/<sub>`; none when the run had no dump folder, so a stale one
    /// is never passed off as this run's.
    pub fn find(dir: &Path, sub: Option<&str>) -> Self {
        let (images, other) = match sub {
            Some(sub) => dumped_files(dir, sub),
            None => (Vec::new(), Vec::new()),
        };
        Dumped { images, other }
    }

    /// True when there is nothing to show.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty() && self.other.is_empty()
    }

    /// The gallery section (nothing when there is nothing to show).
    pub fn section(&self, o: &mut String) {
        let (dumps, dump_other) = (&self.images, &self.other);
        if !dumps.is_empty() || !dump_other.is_empty() {
            let _ = write!(o, "<section id=\"dump\"><h2>Intermediate images</h2><p class=\"note\">What the techniques wrote into <a href=\"dump/\">dump/</a>: shadow maps, warped maps, sample points, tile trees, masks.</p>");
            let mut group = None;
            o.push_str("<div class=\"groups\">");
            for rel in dumps.iter().take(DUMP_GALLERY_MAX) {
                let g = dump_group(rel);
                if group.as_ref() != Some(&g) {
                    if group.is_some() {
                        o.push_str("</div></div>");
                    }
                    let _ = write!(
                        o,
                        "<div class=\"group\"><h3>{}</h3><div class=\"grid gallery\">",
                        esc(&g)
                    );
                    group = Some(g);
                }
                let name = rel.strip_prefix("dump/").unwrap_or(rel);
                let _ = write!(o, "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>", esc(&url(rel)), esc(name));
            }
            if group.is_some() {
                o.push_str("</div></div>");
            }
            o.push_str("</div>");
            if dumps.len() > DUMP_GALLERY_MAX {
                let _ = write!(
                    o,
                    "<p class=\"note\">{} more images in dump/.</p>",
                    dumps.len() - DUMP_GALLERY_MAX
                );
            }
            if !dump_other.is_empty() {
                o.push_str("<p class=\"note\">Other files: ");
                for (i, rel) in dump_other.iter().enumerate() {
                    let name = rel.strip_prefix("dump/").unwrap_or(rel);
                    let sep = if i > 0 { ", " } else { "" };
                    let _ = write!(o, "{sep}<a href=\"{}\">{}</a>", esc(&url(rel)), esc(name));
                }
                o.push_str("</p>");
            }
            o.push_str("</section>\n");
        }
    }
}

/// Files under `DIR/<sub>`, relative to `dir` and sorted: images (PNG, JPEG, GIF, SVG)
/// and everything else.
fn dumped_files(dir: &Path, sub: &str) -> (Vec<String>, Vec<String>) {
    fn walk(root: &Path, d: &Path, out: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(d) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if let Ok(rel) = p.strip_prefix(root) {
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut all = Vec::new();
    walk(dir, &dir.join(sub), &mut all);
    all.sort();
    all.into_iter().partition(|rel| {
        let ext = rel.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
        matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg" | "gif" | "svg"))
    })
}

/// The gallery group of a dumped image: its folder under `dump/`, else its file name up
/// to the first `-` or `_`.
fn dump_group(rel: &str) -> String {
    let inner = rel.strip_prefix("dump/").unwrap_or(rel);
    match inner.split_once('/') {
        Some((d, _)) => d.to_string(),
        None => inner
            .split(['-', '_', '.'])
            .next()
            .unwrap_or(inner)
            .to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dump_groups() {
        assert_eq!(dump_group("dump/afsm/bsp.png"), "afsm");
        assert_eq!(dump_group("dump/sm-depth-0000.png"), "sm");
        assert_eq!(dump_group("dump/psm_post.png"), "psm");
    }
}
