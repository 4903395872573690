//! Hostile input, second round, one test per class: outputs that must not be replaced or
//! written through links, reads that must stay bounded, and failures that must name
//! their true cause. Every run is under a 4 GB address-space limit and killed after 20 s
//! (which fails the test): it must exit 2 (bad input) or 1 (a failed write) with one
//! sentence, or 0 where the input is fine, and never abort, panic or hang.

mod support;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;
use support::{failed_with, ok, refused, tmp, Ran, SHADOWLAB};

/// The address-space limit of every run, in KiB.
const ULIMIT_V_KIB: u64 = 4_000_000;

/// A run taking longer than this has hung.
const TIMEOUT: Duration = Duration::from_secs(20);

fn run(dir: &Path, args: &[&str]) -> Ran {
    run_with(dir, "", args)
}

/// [`run`] with more shell limits (`"ulimit -f 4"`).
fn run_with(dir: &Path, ulimits: &str, args: &[&str]) -> Ran {
    let mut limits = format!("ulimit -v {ULIMIT_V_KIB}");
    if !ulimits.is_empty() {
        limits = format!("{limits}; {ulimits}");
    }
    support::run_limited(dir, &limits, TIMEOUT, args)
}

/// A small render of `scene` to `out.png` with `extra` flags.
fn render(dir: &Path, scene: &str, extra: &[&str]) -> Ran {
    let mut args = vec![
        "render",
        "--scene",
        scene,
        "--technique",
        "sm",
        "--param",
        "resolution=64",
        "--width",
        "32",
        "--height",
        "24",
        "--output",
        "out.png",
    ];
    args.extend_from_slice(extra);
    run(dir, &args)
}

fn mkfifo(path: &Path) {
    let s = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(s.success(), "mkfifo {}", path.display());
}

#[test]
fn dump_folder_files_kept_without_force() {
    let d = tmp("dump");
    std::fs::create_dir(d.join("dump")).unwrap();
    std::fs::write(d.join("dump/sm-map0.png"), b"mine").unwrap();
    let r = render(&d, "bunny", &["--dump", "dump"]);
    refused(&r, &["--dump", "already holds files", "--force"]);
    assert_eq!(std::fs::read(d.join("dump/sm-map0.png")).unwrap(), b"mine");
    assert!(!d.join("out.png").exists());
    // With --force the folder is written into; a new folder needs nothing.
    ok(&render(&d, "bunny", &["--dump", "dump", "--force"]));
    ok(&render(&d, "bunny", &["--dump", "fresh", "--force"]));
    assert!(std::fs::read_dir(d.join("fresh")).unwrap().count() > 0);
}

#[test]
fn output_and_dump_naming_one_path_refused_up_front() {
    let d = tmp("dump-same");
    let r = render(&d, "bunny", &["--dump", "out.png"]);
    refused(&r, &["--output", "--dump", "both name"]);
    assert!(!d.join("out.png").exists(), "nothing is written");
}

#[test]
fn outputs_naming_one_file_through_links_refused() {
    let d = tmp("links");
    std::fs::write(d.join("out.png"), b"old").unwrap();
    std::os::unix::fs::symlink("out.png", d.join("soft.exr")).unwrap();
    std::fs::hard_link(d.join("out.png"), d.join("hard.exr")).unwrap();
    for other in ["soft.exr", "hard.exr"] {
        let r = render(&d, "bunny", &["--visibility", other, "--force"]);
        refused(&r, &["--output", "--visibility", "both name"]);
        assert_eq!(std::fs::read(d.join("out.png")).unwrap(), b"old");
    }
}

#[test]
fn report_links_never_written_through() {
    let d = tmp("report-link");
    let args = [
        "compare",
        "--techniques",
        "sm",
        "--width",
        "32",
        "--height",
        "24",
        "--out",
        "rep",
    ];
    ok(&run(&d, &args));
    std::fs::write(d.join("outside.html"), "my page").unwrap();
    std::fs::remove_file(d.join("rep/index.html")).unwrap();
    std::os::unix::fs::symlink(d.join("outside.html"), d.join("rep/index.html")).unwrap();
    let r = run(&d, &args);
    refused(&r, &["index.html", "symbolic link", "--force"]);
    assert_eq!(
        std::fs::read_to_string(d.join("outside.html")).unwrap(),
        "my page"
    );
    // With --force the link itself is replaced, never the file it points to.
    let mut forced = args.to_vec();
    forced.push("--force");
    ok(&run(&d, &forced));
    assert_eq!(
        std::fs::read_to_string(d.join("outside.html")).unwrap(),
        "my page"
    );
    let meta = std::fs::symlink_metadata(d.join("rep/index.html")).unwrap();
    assert!(meta.file_type().is_file());
}

#[test]
fn bench_outputs_checked_before_the_suite() {
    let d = tmp("bench");
    std::fs::write(d.join("rows.json"), b"mine").unwrap();
    std::fs::write(d.join("plots"), b"a file").unwrap();
    std::os::unix::fs::symlink(d.join("nowhere/x.json"), d.join("dangling.json")).unwrap();
    let bench = |extra: &[&str]| {
        let mut a = vec!["bench", "csm-table", "--quick"];
        a.extend_from_slice(extra);
        run(&d, &a)
    };
    refused(
        &bench(&["--json", "rows.json"]),
        &["--json", "already exists", "--force"],
    );
    assert_eq!(std::fs::read(d.join("rows.json")).unwrap(), b"mine");
    refused(
        &bench(&["--json", "dangling.json", "--force"]),
        &["dangling.json", "symbolic link"],
    );
    refused(&bench(&["--plots", "plots"]), &["--plots", "not a folder"]);
    refused(
        &bench(&["--json", "missing/rows.json"]),
        &["--json", "does not exist"],
    );
    std::fs::create_dir(d.join("figs")).unwrap();
    std::fs::write(d.join("figs/engines-room-error-vs-time.svg"), b"mine").unwrap();
    refused(&bench(&["--plots", "figs"]), &["--plots", "--force"]);
}

#[test]
fn bench_repeat_zero_refused() {
    let d = tmp("repeat");
    let r = run(&d, &["bench", "csm-table", "--quick", "--repeat", "0"]);
    refused(&r, &["--repeat 0", "1..="]);
}

#[test]
fn sparse_nul_files_refused_by_their_first_bytes() {
    let d = tmp("sparse");
    for name in ["zeros.ply", "zeros.obj", "zeros.gltf"] {
        let f = std::fs::File::create(d.join(name)).unwrap();
        // 3 GiB of NUL bytes that take no disk: read whole, they would not fit under
        // the address-space limit of the run.
        f.set_len(3 << 30).unwrap();
        let r = render(&d, name, &[]);
        refused(&r, &[name]);
        assert!(
            r.stderr.contains("NUL") || r.stderr.contains("header") || r.stderr.contains("JSON"),
            "{}",
            r.stderr
        );
    }
}

#[test]
fn view_script_special_files_refused() {
    let d = tmp("script");
    mkfifo(&d.join("steps.fifo"));
    let view = |script: &str| run(&d, &["view", "--scene", "bunny", "--script", script]);
    refused(&view("/dev/zero"), &["--script", "character device"]);
    refused(&view("steps.fifo"), &["--script", "FIFO"]);
    let f = std::fs::File::create(d.join("big.txt")).unwrap();
    f.set_len(3 << 30).unwrap();
    refused(&view("big.txt"), &["--script", "NUL"]);
}

/// A glTF document of one alpha-masked quad per material, `materials` of them, every
/// material's texture reading image `image` (`images` is spliced in as the image list).
fn masked_quads(materials: usize, images: &str, image_of: impl Fn(usize) -> usize) -> String {
    use std::fmt::Write;
    // One quad: positions, texture coordinates, indices (little-endian) in one buffer.
    let pos: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
    let uv: [f32; 8] = [0., 0., 1., 0., 1., 1., 0., 1.];
    let idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bytes: Vec<u8> = pos.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    bytes.extend(idx.iter().flat_map(|v| v.to_le_bytes()));
    let b64 = base64_encode(&bytes);
    let (mut meshes, mut mats, mut texs, mut nodes) =
        (String::new(), String::new(), String::new(), String::new());
    for m in 0..materials {
        let sep = if m == 0 { "" } else { "," };
        let _ = write!(
            meshes,
            r#"{sep}{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":{m}}}]}}"#
        );
        let _ = write!(
            mats,
            r#"{sep}{{"alphaMode":"MASK","pbrMetallicRoughness":{{"baseColorTexture":{{"index":{m}}}}}}}"#
        );
        let _ = write!(texs, r#"{sep}{{"source":{}}}"#, image_of(m));
        let _ = write!(nodes, r#"{sep}{{"mesh":{m},"translation":[{m},0,0]}}"#);
    }
    let scene_nodes: Vec<String> = (0..materials).map(|m| m.to_string()).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{nodes}],
"meshes":[{meshes}],"materials":[{mats}],"textures":[{texs}],"images":[{images}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
{{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},
{{"buffer":0,"byteOffset":80,"byteLength":12}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#,
        scene_nodes.join(","),
        bytes.len()
    )
}

fn base64_encode(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[test]
fn one_image_named_by_many_materials_decoded_once() {
    let d = tmp("texture");
    // An 8192² mask: 64 MiB of alpha decoded, with the decoder's 1 GiB of scratch. Forty
    // copies kept one per material (2.6 GiB) would not fit the 3 GiB the run may use
    // under its 4 GB address-space limit; decoded once and shared, they do.
    let side = 8192;
    let img = image::GrayAlphaImage::from_fn(side, side, |x, _| {
        image::LumaA([0, if x < side / 2 { 0 } else { 255 }])
    });
    img.save(d.join("mask.png")).unwrap();
    let images: Vec<&str> = vec![r#"{"uri":"mask.png"}"#; 40];
    std::fs::write(
        d.join("masks.gltf"),
        masked_quads(40, &images.join(","), |m| m),
    )
    .unwrap();
    ok(&render(&d, "masks.gltf", &["--force"]));
}

#[test]
fn gltf_image_without_uri_or_buffer_view_refused() {
    let d = tmp("image-source");
    std::fs::write(d.join("nosource.gltf"), masked_quads(1, "{}", |_| 0)).unwrap();
    let r = render(&d, "nosource.gltf", &[]);
    refused(&r, &["nosource.gltf", "images[0]", "bufferView"]);
}

#[test]
fn closed_stdout_ends_quietly() {
    let mut fds = [0; 2];
    // SAFETY: pipe writes two descriptors into the array.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // SAFETY: both descriptors were just opened and are owned here.
    let (read, write) = unsafe {
        use std::os::fd::FromRawFd;
        (
            std::os::fd::OwnedFd::from_raw_fd(fds[0]),
            std::os::fd::OwnedFd::from_raw_fd(fds[1]),
        )
    };
    // The reader is gone before the first line is printed.
    drop(read);
    let out = Command::new(SHADOWLAB)
        .arg("scenes")
        .stdout(Stdio::from(write))
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(
        out.status.signal(),
        Some(libc::SIGPIPE),
        "ended by SIGPIPE like cat: {:?}",
        out.status
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn full_stdout_is_one_sentence() {
    let out = Command::new(SHADOWLAB)
        .arg("scenes")
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let r = Ran {
        code: out.status.code(),
        stdout: String::new(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        secs: 0.0,
    };
    failed_with(&r, 1, &["cannot write to stdout", "no space left"]);
    assert!(!r.stderr.contains("bug"), "{}", r.stderr);
}

#[test]
fn file_size_limit_leaves_no_partial_file() {
    let d = tmp("fsize");
    // 4 blocks: far less than the image.
    let r = run_with(
        &d,
        "ulimit -f 4",
        &[
            "render", "--scene", "bunny", "--width", "320", "--height", "240", "--output",
            "out.png",
        ],
    );
    failed_with(&r, 1, &["out.png", "too large"]);
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != ".stderr")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn huge_rotate_axis_rotates() {
    let d = tmp("axis");
    let scene = |axis: &str, angle: f32| {
        format!(
            "[[mesh]]\ngenerator = \"box\"\nrotate_axis = {axis}\nrotate_angle_deg = {angle}\n\
             [camera]\neye = [3.0, 2.5, 4.0]\ntarget = [0.0, 0.0, 0.0]\n\
             [light]\nkind = \"directional\"\ndirection = [0.3, 1.0, 0.5]\n"
        )
    };
    let shot = |name: &str, text: String| {
        std::fs::write(d.join(name), text).unwrap();
        let png = name.replace(".toml", ".png");
        let r = run(
            &d,
            &[
                "render", "--scene", name, "--width", "64", "--height", "48", "--output", &png,
            ],
        );
        ok(&r);
        std::fs::read(d.join(png)).unwrap()
    };
    let huge = shot("huge.toml", scene("[3e38, 3e38, 3e38]", 45.0));
    let unit = shot("unit.toml", scene("[1.0, 1.0, 1.0]", 45.0));
    let none = shot("none.toml", scene("[1.0, 1.0, 1.0]", 0.0));
    assert_eq!(huge, unit, "the huge axis is the unit diagonal");
    assert_ne!(huge, none, "the rotation is applied");
}

#[test]
fn huge_camera_and_light_coordinates_name_their_cause() {
    let d = tmp("coords");
    let r = render(&d, "bunny", &["--camera", "1e38,1e38,1e38:0,0,0"]);
    refused(&r, &["--camera", "camera eye", "beyond"]);
    let r = render(&d, "bunny", &["--camera-distance", "1e30"]);
    refused(&r, &["--camera-distance", "camera eye", "beyond"]);
    let r = render(&d, "bunny", &["--light", "point:1e38,1e38,1e38"]);
    refused(&r, &["point light position", "beyond"]);
    // A direction's length does not matter: scaled first, it is the unit diagonal.
    let r = render(&d, "bunny", &["--light", "directional:1e38,1e38,1e38"]);
    ok(&r);
    let huge = std::fs::read(d.join("out.png")).unwrap();
    ok(&render(
        &d,
        "bunny",
        &["--light", "directional:1,1,1", "--force"],
    ));
    assert_eq!(huge, std::fs::read(d.join("out.png")).unwrap());
}

#[test]
fn repeated_generator_meshes_dropped_before_tracing() {
    // 100,000 copies of one box: 1.2 million triangles and as many materials as copies
    // before the repeats go. What remains is one box and its material, so choosing the
    // automatic light traces 12 triangles, not a scan of 100,000 materials per ray (which
    // took minutes, growing with the square of the copies).
    let d = tmp("boxes");
    let copies = 100_000;
    let text = format!("mesh = [\n{}]\n", "{generator = \"box\"},\n".repeat(copies));
    std::fs::write(d.join("boxes.toml"), text).unwrap();
    let r = support::run_limited(
        &d,
        &format!("ulimit -v {ULIMIT_V_KIB}"),
        TIMEOUT,
        &[
            "render",
            "--scene",
            "boxes.toml",
            "--technique",
            "sm",
            "--width",
            "64",
            "--height",
            "48",
            "--output",
            "out.png",
            "--stats",
            "stats.json",
        ],
    );
    ok(&r);
    let stats = support::read_json(&d.join("stats.json"));
    assert_eq!(stats["triangles"], 12, "{stats}");
    let skipped = format!("skipped {} faces", copies * 12 - 12);
    assert!(stats["warnings"].to_string().contains(&skipped), "{stats}");
}
