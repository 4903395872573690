//! `--up` and OBJ cut-outs on the command line: a Z-up file turned upright is measured
//! like its Y-up twin and says so in `metrics.json` and the stats; bad axes and `map_d`
//! images that cannot be used are refused by name with exit 2.

mod support;

use std::path::Path;
use support::{data, quiet as bin, refused, tmp, Capture, Ran};

fn render(dir: &Path, scene: &Path, extra: &[&str]) -> Ran {
    bin()
        .args([
            "render",
            "--technique",
            "sm",
            "--width",
            "32",
            "--height",
            "24",
        ])
        .arg("--scene")
        .arg(scene)
        .arg("--output")
        .arg(dir.join("out.png"))
        .arg("--force")
        .args(extra)
        .ran()
}

#[test]
fn bad_up_axes_are_refused_by_name() {
    let d = tmp("bad-up");
    let cards = data("masked/cards.obj");
    for bad in ["w", "up", "zz", "-"] {
        let r = render(&d, &cards, &[&format!("--up={bad}")]);
        refused(&r, &["--up", &format!("{bad:?}")]);
    }
    let r = bin()
        .args(["render", "--scene", "bunny", "--up", "z", "--output"])
        .arg(d.join("out.png"))
        .ran();
    refused(&r, &["--up z", "bunny"]);
    let r = render(&d, &cards, &["--obj-kd-alpha", "maybe"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("--obj-kd-alpha"), "{}", r.stderr);
}

#[test]
fn a_z_up_file_with_up_z_measures_as_its_y_up_twin() {
    let d = tmp("z-up");
    let compare = |scene: &str, out: &str, extra: &[&str]| {
        let dir = d.join(out);
        let r = bin()
            .args(["compare", "--techniques", "afsm,raytrace", "--width", "96"])
            .args(["--height", "72", "--scene"])
            .arg(data(scene))
            .arg("--out")
            .arg(&dir)
            .args(extra)
            .ran();
        support::ok(&r);
        support::metrics(&dir)
    };
    let y = compare("masked/cards.obj", "y", &[]);
    let z = compare("masked/cards-zup.obj", "z", &["--up", "z"]);
    assert_eq!(z["up"], "z");
    assert_eq!(y["up"], "y");
    assert_eq!(y["obj_kd_alpha"], true);
    assert_eq!(z["camera"], y["camera"]);
    assert_eq!(z["light"], y["light"]);
    assert_eq!(z["covered_pixels"], y["covered_pixels"]);
    for m in [&y, &z] {
        for r in m["results"].as_array().unwrap() {
            assert_eq!(r["mismatch_rate"], 0.0, "{}: {r}", r["technique"]);
        }
    }
    let stats = d.join("stats.json");
    let r = render(
        &d,
        &data("masked/cards-zup.obj"),
        &[
            "--up",
            "z",
            "--obj-kd-alpha",
            "false",
            "--stats",
            stats.to_str().unwrap(),
        ],
    );
    support::ok(&r);
    let s = support::read_json(&stats);
    assert_eq!(s["up"], "z", "{s}");
    assert_eq!(s["obj_kd_alpha"], false, "{s}");
}

/// A folder with `cards.obj` whose material `leafy` has `map_d` `image`, holding `bytes`.
fn with_map_d(name: &str, image: &str, bytes: Option<&[u8]>) -> std::path::PathBuf {
    let d = tmp(name);
    std::fs::write(
        d.join("cards.obj"),
        "mtllib cards.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl leafy\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(
        d.join("cards.mtl"),
        format!("newmtl leafy\nmap_d {image}\n"),
    )
    .unwrap();
    if let Some(b) = bytes {
        std::fs::write(d.join(image), b).unwrap();
    }
    d
}

/// A PNG claiming `w` x `h` RGBA texels: its signature, header, a few compressed bytes
/// and its end (what a decoder reads before it knows the size).
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut ihdr = Vec::new();
    ihdr.extend(w.to_be_bytes());
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 6, 0, 0, 0]);
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    for (kind, data) in [
        (b"IHDR", ihdr),
        (b"IDAT", vec![0x78, 0x9c, 0x63, 0, 0, 0, 1, 0, 1]),
        (b"IEND", vec![]),
    ] {
        let mut c = kind.to_vec();
        c.extend(&data);
        out.extend((data.len() as u32).to_be_bytes());
        out.extend(&c);
        out.extend(crc32(&c).to_be_bytes());
    }
    out
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn unusable_map_d_images_are_refused_by_name() {
    let d = with_map_d("map-d-text", "mask.png", Some(b"not an image at all"));
    let r = render(&d, &d.join("cards.obj"), &[]);
    refused(&r, &["cards.obj", "leafy", "mask.png", "decoded"]);

    let d = with_map_d("map-d-huge", "huge.png", Some(&png_header(20000, 20000)));
    let r = render(&d, &d.join("cards.obj"), &[]);
    refused(&r, &["leafy", "huge.png", "20000x20000"]);

    let d = with_map_d("map-d-dir", "folder.png", None);
    std::fs::create_dir_all(d.join("folder.png")).unwrap();
    let r = render(&d, &d.join("cards.obj"), &[]);
    refused(&r, &["leafy", "folder.png", "not a regular file"]);

    let d = with_map_d("map-d-outside", "../outside.png", None);
    let r = render(&d, &d.join("cards.obj"), &[]);
    refused(&r, &["leafy", "outside.png", "outside"]);

    // A map_d that is not there leaves the material whole, with a warning.
    let d = with_map_d("map-d-missing", "gone.png", None);
    let r = render(&d, &d.join("cards.obj"), &[]);
    support::ok(&r);
    assert!(
        r.stderr.contains("gone.png") && r.stderr.contains("does not exist"),
        "{}",
        r.stderr
    );
}
