//! The panel's text: the technique and its main parameter, the frame time per stage, the
//! error against the reference, the technique's image shown, the last message and the
//! keys.

use super::frame::Drawn;
use super::session::Session;
use shadowlab::techniques::param_text;

/// The keys, two lines.
const KEYS: [&str; 2] = [
    "WASD EQ fly, drag: left look, right light",
    "Tab technique  [ ] param  R error  M images  H hide  P shot",
];

/// The panel's lines for the frame `d` of session `s`; `times` are the whole time of the
/// last frame drawn and of the last presentation, `error` the error line when that
/// overlay is on.
pub fn lines(s: &Session, d: &Drawn, times: (f64, f64), error: Option<String>) -> Vec<String> {
    let (frame_ms, present_ms) = times;
    let mut out = Vec::new();
    let param = match s.main_param() {
        Some((k, _, v)) => format!("  {k} {}", param_text(&v)),
        None => String::new(),
    };
    let progress = match s.technique.converged() {
        Some(false) => "  (refining)",
        _ => "",
    };
    out.push(format!("{}{param}{progress}", s.name));
    out.push(format!(
        "frame {frame_ms:.1} ms ({:.1} fps)",
        1e3 / frame_ms.max(1e-3)
    ));
    for (name, ms) in &d.stages_ms {
        out.push(format!("  {name:<20} {ms:>7.1} ms"));
    }
    out.push(format!(
        "  {:<20} {present_ms:>7.1} ms",
        super::app::PRESENT
    ));
    out.extend(error);
    if let Some(i) = s.show.dump {
        if let Some((name, _)) = d.dumps.get(i) {
            out.push(format!("image {} of {}: {name}", i + 1, d.dumps.len()));
        }
    }
    if !s.status.is_empty() {
        out.push(s.status.clone());
    }
    out.extend(KEYS.iter().map(|k| k.to_string()));
    out
}
