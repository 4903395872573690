//! Shadows in motion, as `compare --frames N` measures them: every frame judged against
//! the reference traced for it, and the temporal error by reprojection — on `street`'s
//! sideways dolly the uniform and perspective maps, refitted to the view each frame,
//! shimmer while the alias-free map, exact in every frame, does not; along `room`'s path
//! the adaptive map's error falls as it refines.

mod support;

use serde_json::Value;
use std::path::Path;
use support::{metrics, quiet as bin, run_ok as run, tmp};

/// `compare` on `scene` with `techniques` over `frames` frames at `w`×`h`; its metrics.
fn sequence(out: &Path, scene: &str, techniques: &str, frames: u32, (w, h): (u32, u32)) -> Value {
    run(bin()
        .args(["compare", "--scene", scene, "--techniques", techniques])
        .args(["--frames", &frames.to_string()])
        .args(["--width", &w.to_string(), "--height", &h.to_string()])
        .arg("--out")
        .arg(out));
    metrics(out)
}

/// The result of `technique`.
fn result<'a>(m: &'a Value, technique: &str) -> &'a Value {
    m["results"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["technique"] == technique)
        .unwrap_or_else(|| panic!("no result for {technique}"))
}

/// A per-frame figure of a result, one per frame.
fn per_frame(r: &Value, key: &str) -> Vec<Option<f64>> {
    r["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            assert!(f.get(key).is_some(), "frame without {key}: {f}");
            f[key].as_f64()
        })
        .collect()
}

/// Width, height and frame count of an animated GIF.
fn gif(path: &Path) -> (u32, u32, usize) {
    use image::AnimationDecoder;
    let f = std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    );
    let frames = image::codecs::gif::GifDecoder::new(f)
        .unwrap()
        .into_frames()
        .collect_frames()
        .unwrap();
    let (w, h) = frames[0].buffer().dimensions();
    (w, h, frames.len())
}

#[test]
fn on_the_street_dolly_uniform_and_perspective_maps_shimmer_and_the_alias_free_map_does_not() {
    let out = tmp("street").join("report");
    let (w, h) = (320, 240);
    let m = sequence(&out, "street", "sm,psm,afsm", 4, (w, h));
    let covered = m["covered_pixels"].as_f64().unwrap();
    let mut temporal = std::collections::BTreeMap::new();
    for t in ["sm", "psm", "afsm"] {
        let r = result(&m, t);
        let errors = per_frame(r, "mean_abs_error");
        let mismatches = per_frame(r, "mismatch_rate");
        assert_eq!(errors.len(), 4, "{t}");
        assert!(errors.iter().chain(&mismatches).all(Option::is_some), "{t}");
        // The last frame is the one the run's own verdict describes, against the same
        // reference.
        assert_eq!(errors[3], r["mean_abs_error"].as_f64(), "{t}");
        assert_eq!(mismatches[3], r["mismatch_rate"].as_f64(), "{t}");
        let each = per_frame(r, "temporal_error");
        assert!(
            each[0].is_none() && each[1..].iter().all(Option::is_some),
            "{t}: {each:?}"
        );
        // A sideways dolly keeps most of the view from one frame to the next.
        for p in &per_frame(r, "reprojected_pixels")[1..] {
            assert!(
                p.unwrap() > 0.8 * covered,
                "{t}: {p:?} of {covered} reprojected"
            );
        }
        let mean = r["temporal_error"].as_f64().unwrap();
        let expected = each[1..].iter().map(|e| e.unwrap()).sum::<f64>() / 3.0;
        assert!((mean - expected).abs() <= 1e-12 * expected.max(1.0), "{t}");
        temporal.insert(t, mean);
        // The reference and the technique side by side, one frame per frame.
        let walk = out.join(r["walkthrough"].as_str().unwrap());
        assert_eq!(gif(&walk), (2 * w + 8, h, 4), "{t}");
    }
    let afsm = temporal["afsm"];
    assert!(
        afsm <= 1e-6,
        "afsm is exact in every frame: temporal error {afsm}"
    );
    for t in ["sm", "psm"] {
        assert!(
            temporal[t] >= 1e-4 && temporal[t] >= 5.0 * afsm,
            "{t}: temporal error {} against afsm's {afsm}",
            temporal[t]
        );
    }
    for p in ["temporal-error", "frame-errors"] {
        assert!(out.join(format!("plots/{p}.svg")).is_file(), "no {p} plot");
    }
}

#[test]
fn along_the_room_walk_the_adaptive_maps_error_falls_as_it_refines() {
    let out = tmp("room").join("report");
    let m = sequence(&out, "room", "asm,sm", 8, (512, 384));
    let asm: Vec<f64> = per_frame(result(&m, "asm"), "mean_abs_error")
        .into_iter()
        .map(Option::unwrap)
        .collect();
    let sm: Vec<f64> = per_frame(result(&m, "sm"), "mean_abs_error")
        .into_iter()
        .map(Option::unwrap)
        .collect();
    assert_eq!(asm.len(), 8);
    // While the camera walks slowly into the room at the path's pace, asm's error falls
    // frame after frame as the refinement catches up, and falls further than a stateless
    // standard map's on the same frames (which moves only with what the view shows).
    for i in 1..asm.len() {
        assert!(asm[i] <= asm[i - 1], "asm per frame: {asm:?}");
    }
    assert!(asm[7] < 0.5 * asm[0], "asm per frame: {asm:?}");
    assert!(
        asm[7] / asm[0] < 0.75 * (sm[7] / sm[0]),
        "asm {asm:?} against sm {sm:?}"
    );
}
