//! Text of the report page: HTML escaping, relative URLs, byte counts, and table cells
//! that fold what does not fit.

use std::fmt::Write as _;

/// `s` with HTML's special characters escaped, for text and attribute values.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// A relative path as a URL: each component percent-encoded where needed.
pub fn url(rel: &str) -> String {
    let mut s = String::new();
    for b in rel.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            s.push(b as char);
        } else {
            let _ = write!(s, "%{b:02X}");
        }
    }
    s
}

/// A byte count in B, KiB or MiB.
pub fn bytes(n: f64) -> String {
    if n >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", n / (1024.0 * 1024.0))
    } else if n >= 1024.0 {
        format!("{:.1} KiB", n / 1024.0)
    } else {
        format!("{n:.0} B")
    }
}

/// Table cells show at most this many parameters or counters; the rest unfold on a click,
/// so every row stays a line or two tall.
const CELL_ITEMS: usize = 4;

/// `items` joined, those past [`CELL_ITEMS`] folded into a `<details>`.
pub fn folded(items: &[String]) -> String {
    if items.len() <= CELL_ITEMS + 1 {
        return items.join(" ");
    }
    format!(
        "<details><summary>{} <span class=\"more\">+{} more</span></summary>{}</details>",
        items[..CELL_ITEMS].join(" "),
        items.len() - CELL_ITEMS,
        items[CELL_ITEMS..].join(" ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_escaped() {
        assert_eq!(url("plots/a b#.svg"), "plots/a%20b%23.svg");
        assert_eq!(esc("<a href=\"x\">"), "&lt;a href=&quot;x&quot;&gt;");
    }
}
