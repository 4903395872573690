//! Hostile input, one test per class: special files, count amplification, limits that
//! must fit, outputs that must not be overwritten, nonsense that must be refused, late or
//! misleading errors, reads outside the scene's folder, and the triangle limit with the
//! ground plane. Every input is made here; every run is under a 4 GB address-space limit
//! (`ulimit -v 4000000`) and killed after 20 s: it must exit 2 with one sentence, or 0
//! where the input is fine, and never abort, panic or hang.

mod support;

use std::path::Path;
use std::process::Command;
use std::time::Duration;
use support::{ok, refused, tmp, Ran};

/// The address-space limit of every run, in KiB.
const ULIMIT_V_KIB: &str = "4000000";

/// A run taking longer than this has hung.
const TIMEOUT: Duration = Duration::from_secs(20);

/// Runs `shadowlab --quiet ARGS` in `dir` under the address-space limit, killing it after
/// [`TIMEOUT`] (which fails the test).
fn run(dir: &Path, args: &[&str]) -> Ran {
    support::run_limited(dir, &format!("ulimit -v {ULIMIT_V_KIB}"), TIMEOUT, args)
}

/// Small, fast render flags: the output goes to `out.png` in the run's folder.
const FAST: &[&str] = &[
    "--technique",
    "sm",
    "--param",
    "resolution=64",
    "--width",
    "32",
    "--height",
    "24",
    "--force",
];

fn render(dir: &Path, scene: &str, extra: &[&str]) -> Ran {
    let mut args = vec!["render", "--scene", scene, "--output", "out.png"];
    args.extend_from_slice(FAST);
    args.extend_from_slice(extra);
    run(dir, &args)
}

fn mkfifo(path: &Path) {
    let s = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(s.success(), "mkfifo {}", path.display());
}

/// One triangle's three positions as little-endian f32.
fn triangle_bytes() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// A glTF document with one non-indexed triangle read from buffer `uri` of
/// `byte_length` bytes; `extra` is spliced into the top-level object.
fn gltf_triangle(uri: &str, byte_length: usize, extra: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"uri":{uri:?},"byteLength":{byte_length}}}]{extra}}}"#
    )
}

#[test]
fn special_files() {
    let d = tmp("special");
    // A FIFO as the scene, as a glTF buffer, as an OBJ material library and as a TOML
    // mesh file: refused at once, by name.
    mkfifo(&d.join("pipe.obj"));
    mkfifo(&d.join("pipe.bin"));
    mkfifo(&d.join("pipe.mtl"));
    let r = render(&d, "pipe.obj", &[]);
    refused(&r, &["pipe.obj", "FIFO"]);
    assert!(r.secs < 5.0, "took {} s", r.secs);
    std::fs::write(
        d.join("fifo-buffer.gltf"),
        gltf_triangle("pipe.bin", 36, ""),
    )
    .unwrap();
    refused(&render(&d, "fifo-buffer.gltf", &[]), &["buffer 0", "FIFO"]);
    std::fs::write(
        d.join("fifo-mtl.obj"),
        "mtllib pipe.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    refused(&render(&d, "fifo-mtl.obj", &[]), &["pipe.mtl", "FIFO"]);
    std::fs::write(d.join("fifo-mesh.toml"), "[[mesh]]\nfile = \"pipe.obj\"\n").unwrap();
    refused(&render(&d, "fifo-mesh.toml", &[]), &["pipe.obj", "FIFO"]);
    // Devices: as the scene, and (where references may leave the folder) as a buffer
    // and a material library.
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.obj")).unwrap();
    refused(
        &render(&d, "zero.obj", &[]),
        &["zero.obj", "character device"],
    );
    std::fs::write(
        d.join("urandom.gltf"),
        gltf_triangle("/dev/urandom", 36, ""),
    )
    .unwrap();
    let outside = ["--allow-outside-scene-dir"];
    refused(
        &render(&d, "urandom.gltf", &outside),
        &["buffer 0", "character device"],
    );
    std::fs::write(
        d.join("zero-mtl.obj"),
        "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    refused(
        &render(&d, "zero-mtl.obj", &outside),
        &["/dev/zero", "character device"],
    );
    // A folder as the scene.
    std::fs::create_dir_all(d.join("folder.ply")).unwrap();
    refused(&render(&d, "folder.ply", &[]), &["folder.ply", "folder"]);
    // A buffer declaring 44 bytes whose file is 3.2 GB (sparse): only 44 bytes are read.
    let big = std::fs::File::create(d.join("big.bin")).unwrap();
    use std::io::Write;
    (&big).write_all(&triangle_bytes()).unwrap();
    big.set_len(3_200_000_000).unwrap();
    std::fs::write(d.join("big.gltf"), gltf_triangle("big.bin", 44, "")).unwrap();
    let r = render(&d, "big.gltf", &[]);
    ok(&r);
    assert!(r.secs < 10.0, "took {} s", r.secs);
}

#[test]
fn count_amplification() {
    let d = tmp("amplification");
    // 542 bytes of glTF: a sparse POSITION accessor of 48M elements and no buffer view.
    let sparse = r#"{"asset":{"version":"2.0"},"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"accessors":[{"componentType":5126,"count":48000000,"type":"VEC3",
"sparse":{"count":1,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":1}}}],
"bufferViews":[{"buffer":0,"byteLength":4},{"buffer":0,"byteOffset":4,"byteLength":12}],
"buffers":[{"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAA==","byteLength":16}]}"#;
    std::fs::write(d.join("sparse.gltf"), sparse).unwrap();
    refused(
        &render(&d, "sparse.gltf", &[]),
        &["sparse.gltf", "16000000 triangles", "MiB"],
    );
    // A glTF with 10⁷ nodes: counted before they are decoded.
    let mut nodes = String::from(r#"{"asset":{"version":"2.0"},"nodes":["#);
    nodes.push_str(&"{},".repeat(10_000_000));
    nodes.push_str("{}]}");
    std::fs::write(d.join("nodes.gltf"), nodes).unwrap();
    refused(&render(&d, "nodes.gltf", &[]), &["10000001 nodes", "limit"]);
    // 2²¹ instances of one triangle through a chain of nodes that each list the next
    // twice (a 1 KB file).
    let mut chain: Vec<String> = (0..21)
        .map(|k| format!(r#"{{"children":[{},{}]}}"#, k + 1, k + 1))
        .collect();
    chain.push(r#"{"mesh":0}"#.into());
    let dag = gltf_triangle(&tri_data_uri(), 36, "").replace(
        r#""nodes":[{"mesh":0}]"#,
        &format!(r#""nodes":[{}]"#, chain.join(",")),
    );
    std::fs::write(d.join("dag.gltf"), dag).unwrap();
    refused(&render(&d, "dag.gltf", &[]), &["dag.gltf", "limit"]);
    // A binary PLY whose face lists all claim 255 vertices, 40,000 of them.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 40000\nproperty list uchar int vertex_indices\n\
end_header\n"
        .to_vec();
    ply.extend(triangle_bytes());
    let face: Vec<u8> = std::iter::once(255u8)
        .chain((0..255u32).flat_map(|k| (k % 3).to_le_bytes()))
        .collect();
    for _ in 0..40_000 {
        ply.extend(&face);
    }
    std::fs::write(d.join("fans.ply"), ply).unwrap();
    let r = render(&d, "fans.ply", &[]);
    refused(&r, &["fans.ply", "10120000 triangles"]);
    // A PLY whose header claims a billion faces in a file of a few hundred bytes.
    let liar = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1000000000\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::fs::write(d.join("liar.ply"), liar).unwrap();
    refused(&render(&d, "liar.ply", &[]), &["liar.ply", "1000000000"]);
    // 10⁷ copies of `f 1 2 3` (80 MB): counted and estimated before tobj builds them.
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    obj.push_str(&"f 1 2 3\n".repeat(10_000_000));
    std::fs::write(d.join("faces.obj"), obj).unwrap();
    let r = render(&d, "faces.obj", &[]);
    refused(&r, &["faces.obj", "10000000 triangles"]);
    // A TOML camera path of 10⁷ key frames is far larger than a scene file may be; one
    // of 200,000 is within the size but above the key-frame limit.
    let key = "{ eye = [0, 0, 3], target = [0, 0, 0] },\n";
    let path = |n: usize| {
        format!(
            "[camera]\neye = [0, 0, 3]\ntarget = [0, 0, 0]\npath = [\n{}]\n[[mesh]]\ngenerator = \"box\"\n",
            key.repeat(n)
        )
    };
    std::fs::write(d.join("keys.toml"), path(10_000_000)).unwrap();
    refused(&render(&d, "keys.toml", &[]), &["keys.toml", "larger than"]);
    std::fs::write(d.join("keys2.toml"), path(200_000)).unwrap();
    refused(
        &render(&d, "keys2.toml", &[]),
        &["keys2.toml", "200000 key frames"],
    );
}

/// One triangle as a `data:` URI.
fn tri_data_uri() -> String {
    const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let bytes = triangle_bytes();
    let mut s = String::from("data:application/octet-stream;base64,");
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[test]
fn limits_fit_or_are_refused_up_front() {
    let d = tmp("limits");
    let base = ["render", "--scene", "bunny", "--technique", "sm", "--force"];
    let with = |extra: &[&str]| {
        let mut a: Vec<&str> = base.to_vec();
        a.extend_from_slice(extra);
        a.extend_from_slice(&["--output", "out.png"]);
        run(&d, &a)
    };
    // The largest image the camera allows does not fit in 4 GB: refused before the
    // camera pass, naming the flags and the estimate.
    let r = with(&["--width", "8192", "--height", "8192"]);
    refused(&r, &["8192x8192", "--width/--height", "MiB"]);
    assert!(r.secs < 5.0, "took {} s", r.secs);
    // A 16384² map takes 4 GiB while it is rasterized.
    refused(
        &with(&["--param", "resolution=16384"]),
        &["sm.resolution = 16384", "MiB"],
    );
    // A point light at 8192: six maps.
    refused(
        &with(&["--param", "resolution=8192", "--light", "point:0,1,0"]),
        &["6 light map(s)", "MiB"],
    );
    // What does fit runs.
    ok(&with(&[
        "--param",
        "resolution=2048",
        "--width",
        "320",
        "--height",
        "240",
    ]));
    // --sweep with 100,000 values, in ten flags (one argument may hold 128 KiB).
    let sweeps: Vec<String> = (0..10)
        .map(|k| {
            let values: Vec<String> = (1..=10_000).map(|v| (k * 10_000 + v).to_string()).collect();
            format!("sm.resolution={}", values.join(","))
        })
        .collect();
    let mut args = vec!["compare", "--techniques", "sm", "--out", "rep"];
    for s in &sweeps {
        args.extend(["--sweep", s.as_str()]);
    }
    let r = run(&d, &args);
    refused(&r, &["--sweep", "10000 values", "limit"]);
    assert!(!d.join("rep").exists());
}

#[test]
fn outputs_never_overwritten() {
    let d = tmp("outputs");
    // A frame of the sequence exists already.
    std::fs::write(d.join("a-0001.png"), b"keep").unwrap();
    let r = run(
        &d,
        &[
            "render",
            "--scene",
            "bunny",
            "--technique",
            "sm",
            "--frames",
            "3",
            "--output",
            "a.png",
            "--width",
            "32",
            "--height",
            "24",
        ],
    );
    refused(&r, &["a-0001.png", "already exists", "--force"]);
    assert_eq!(std::fs::read(d.join("a-0001.png")).unwrap(), b"keep");
    assert!(!d.join("a.png").exists() && !d.join("a-0000.png").exists());
    // The shaded image and the statistics in one file.
    let r = run(
        &d,
        &[
            "render", "--scene", "bunny", "--output", "s.png", "--stats", "s.png",
        ],
    );
    refused(&r, &["--stats", "s.png"]);
    assert!(!d.join("s.png").exists());
    // A folder with a metrics.json of its own is not a report.
    let user = d.join("mine");
    std::fs::create_dir_all(&user).unwrap();
    std::fs::write(user.join("metrics.json"), "{}").unwrap();
    std::fs::write(user.join("index.html"), "my page").unwrap();
    let r = run(
        &d,
        &[
            "compare",
            "--techniques",
            "sm",
            "--width",
            "32",
            "--height",
            "24",
            "--out",
            "mine",
        ],
    );
    refused(&r, &["mine", "not a shadowlab report"]);
    assert_eq!(
        std::fs::read_to_string(user.join("index.html")).unwrap(),
        "my page"
    );
    // A report shadowlab wrote may be written again.
    let again = [
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
    ok(&run(&d, &again));
    ok(&run(&d, &again));
    // --output through a dangling symbolic link.
    std::os::unix::fs::symlink(d.join("nowhere/target.png"), d.join("link.png")).unwrap();
    let r = run(
        &d,
        &[
            "render", "--scene", "bunny", "--output", "link.png", "--force",
        ],
    );
    refused(&r, &["link.png", "symbolic link"]);
    assert!(!d.join("nowhere").exists());
}

#[test]
fn nonsense_refused() {
    let d = tmp("nonsense");
    let toml = |name: &str, text: &str| {
        std::fs::write(d.join(name), text).unwrap();
        render(&d, name, &[])
    };
    let scene = "[[mesh]]\ngenerator = \"box\"\n";
    refused(
        &toml(
            "eye.toml",
            &format!("[camera]\neye = [0, 0, 3, 99]\ntarget = [0, 0, 0]\n{scene}"),
        ),
        &["eye.toml", "expected 3 numbers", "found 4"],
    );
    refused(
        &toml(
            "translate.toml",
            &format!("{scene}translate = [1, 2, 3, 4, 5]\n"),
        ),
        &["translate.toml", "found 5"],
    );
    let version = gltf_triangle(&tri_data_uri(), 36, "").replace(r#""2.0""#, r#""3.0""#);
    std::fs::write(d.join("v3.gltf"), version).unwrap();
    refused(&render(&d, "v3.gltf", &[]), &["v3.gltf", "asset version"]);
    let spot = gltf_triangle(
        &tri_data_uri(),
        36,
        r#","extensionsUsed":["KHR_lights_punctual"],"extensions":{"KHR_lights_punctual":{"lights":[{"type":"spot","spot":{"outerConeAngle":100}}]}}"#,
    )
    .replace(
        r#""nodes":[0]"#,
        r#""nodes":[0,1]"#,
    )
    .replace(
        r#""nodes":[{"mesh":0}]"#,
        r#""nodes":[{"mesh":0},{"translation":[0,2,0],"extensions":{"KHR_lights_punctual":{"light":0}}}]"#,
    );
    std::fs::write(d.join("spot.gltf"), spot).unwrap();
    refused(
        &render(&d, "spot.gltf", &[]),
        &["spot.gltf", "outerConeAngle 100"],
    );
    let ply = "ply\nformat ascii 7.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::fs::write(d.join("v7.ply"), ply).unwrap();
    refused(&render(&d, "v7.ply", &[]), &["v7.ply", "7.0"]);
    // GLB files whose header length or chunk length lie.
    let json = gltf_triangle("", 36, "").replace(r#""uri":"","#, "");
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = triangle_bytes();
    bin.resize(36, 0);
    let glb = |total: u32, json_len: u32| {
        let mut g = b"glTF".to_vec();
        g.extend(2u32.to_le_bytes());
        g.extend(total.to_le_bytes());
        g.extend(json_len.to_le_bytes());
        g.extend(b"JSON");
        g.extend(&json);
        g.extend((bin.len() as u32).to_le_bytes());
        g.extend(b"BIN\0");
        g.extend(&bin);
        g
    };
    let honest = glb(0, json.len() as u32);
    let total = honest.len() as u32;
    std::fs::write(d.join("ok.glb"), glb(total, json.len() as u32)).unwrap();
    ok(&render(&d, "ok.glb", &[]));
    std::fs::write(d.join("long.glb"), glb(total + 1000, json.len() as u32)).unwrap();
    refused(&render(&d, "long.glb", &[]), &["long.glb", "GLB header"]);
    std::fs::write(d.join("chunk.glb"), glb(total, json.len() as u32 + 4000)).unwrap();
    refused(&render(&d, "chunk.glb", &[]), &["chunk.glb", "chunk 0"]);
    // An output whose extension is not the documented format's.
    let r = run(&d, &["render", "--scene", "bunny", "--output", "x.jpg"]);
    refused(&r, &["--output", "x.jpg", ".png"]);
    assert!(!d.join("x.jpg").exists());
}

#[test]
fn late_or_misleading_errors() {
    let d = tmp("late");
    // Outputs are checked before the render: nothing is written.
    let r = run(
        &d,
        &["render", "--scene", "bunny", "--visibility", "vis.png"],
    );
    refused(&r, &["--visibility", "vis.png", ".exr"]);
    assert!(r.secs < 5.0 && !d.join("vis.png").exists() && !d.join("shadowlab.png").exists());
    refused(
        &run(&d, &["render", "--scene", "bunny", "--output", "x.exr"]),
        &["--output", ".png"],
    );
    assert!(!d.join("x.exr").exists());
    // A scene that does not load leaves no report folder behind.
    let r = run(&d, &["compare", "--scene", "missing.obj", "--out", "D"]);
    refused(&r, &["missing.obj", "does not exist"]);
    assert!(!d.join("D").exists());
    // The cause once, not twice.
    assert_eq!(
        r.stderr.matches("does not exist").count(),
        1,
        "{}",
        r.stderr
    );
    // Degenerate cameras name the file or the flag.
    let zeros = gltf_triangle(
        &tri_data_uri(),
        36,
        r#","cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}]"#,
    )
    .replace(r#""nodes":[0]"#, r#""nodes":[0,1]"#)
    .replace(
        r#""nodes":[{"mesh":0}]"#,
        r#""nodes":[{"mesh":0},{"camera":0,"matrix":[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}]"#,
    );
    std::fs::write(d.join("zeros.gltf"), zeros).unwrap();
    refused(&render(&d, "zeros.gltf", &[]), &["zeros.gltf", "camera 0"]);
    std::fs::write(
        d.join("tiny.toml"),
        "[[mesh]]\ngenerator = \"box\"\nscale = 1e-38\n",
    )
    .unwrap();
    refused(&render(&d, "tiny.toml", &[]), &["tiny.toml", "camera"]);
    refused(
        &render(&d, "bunny", &["--camera-distance", "1e-38"]),
        &["--camera-distance", "same point"],
    );
    // An OBJ at ±3e38: the file is named, not the ground plane added under it.
    std::fs::write(
        d.join("huge.obj"),
        "v -3e38 0 0\nv 3e38 0 0\nv 0 3e38 0\nf 1 2 3\n",
    )
    .unwrap();
    let r = render(&d, "huge.obj", &[]);
    refused(&r, &["huge.obj"]);
    assert!(!r.stderr.contains("triangle 1"), "{}", r.stderr);
    // OBJ errors carry their line.
    std::fs::write(d.join("line.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n").unwrap();
    refused(&render(&d, "line.obj", &[]), &["line.obj", "line 5"]);
    // A TOML mesh file that is a FIFO or a folder says so.
    mkfifo(&d.join("p.ply"));
    std::fs::create_dir_all(d.join("dir.obj")).unwrap();
    std::fs::write(d.join("fifo.toml"), "[[mesh]]\nfile = \"p.ply\"\n").unwrap();
    refused(&render(&d, "fifo.toml", &[]), &["p.ply", "FIFO"]);
    std::fs::write(d.join("dir.toml"), "[[mesh]]\nfile = \"dir.obj\"\n").unwrap();
    let r = render(&d, "dir.toml", &[]);
    refused(&r, &["dir.obj", "folder"]);
    assert!(!r.stderr.contains("does not exist"), "{}", r.stderr);
}

#[test]
fn reads_outside_the_scene_folder() {
    let d = tmp("outside");
    let scene = d.join("scene");
    std::fs::create_dir_all(&scene).unwrap();
    std::fs::write(d.join("outside.bin"), triangle_bytes()).unwrap();
    for (name, uri) in [
        ("passwd.gltf", "/etc/passwd"),
        ("dotdot.gltf", "../outside.bin"),
        ("encoded.gltf", "%2e%2e/outside.bin"),
        ("fileuri.gltf", "file:///etc/passwd"),
    ] {
        std::fs::write(scene.join(name), gltf_triangle(uri, 36, "")).unwrap();
        let r = render(&d, &format!("scene/{name}"), &[]);
        refused(
            &r,
            &[
                name,
                "outside the scene's folder",
                "--allow-outside-scene-dir",
            ],
        );
        assert!(!r.stderr.contains("root:"), "{}", r.stderr);
    }
    // An index out of range over a file's bytes does not print them.
    let text = "root:x:0:0:root:/root:/bin/sh\n".repeat(4);
    std::fs::write(scene.join("secret.bin"), &text).unwrap();
    let indexed = gltf_triangle("secret.bin", text.len(), "")
        .replace(
            r#""attributes":{"POSITION":0}"#,
            r#""attributes":{"POSITION":0},"indices":1"#,
        )
        .replace(
            r#""accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}]"#,
            r#""accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},{"bufferView":0,"componentType":5125,"count":3,"type":"SCALAR"}]"#,
        );
    std::fs::write(scene.join("secret.gltf"), indexed).unwrap();
    let r = render(&d, "scene/secret.gltf", &[]);
    refused(&r, &["secret.gltf", "out of range"]);
    for word in text.as_bytes().chunks(4) {
        let n = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
        assert!(!r.stderr.contains(&n.to_string()), "{}", r.stderr);
    }
    // TOML mesh files likewise; the flag allows them.
    std::fs::write(
        d.join("outside.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        scene.join("up.toml"),
        "[[mesh]]\nfile = \"../outside.obj\"\n",
    )
    .unwrap();
    refused(
        &render(&d, "scene/up.toml", &[]),
        &["up.toml", "outside the scene's folder"],
    );
    ok(&render(&d, "scene/up.toml", &["--allow-outside-scene-dir"]));
    ok(&render(
        &d,
        "scene/dotdot.gltf",
        &["--allow-outside-scene-dir"],
    ));
}

#[test]
fn triangle_limit_with_ground_plane() {
    let d = tmp("ground");
    // 200 triangles instanced 250,000 times through two levels of nodes: exactly the
    // scene's limit of 50,000,000 before the two ground-plane triangles are added.
    let instanced = |per_mesh: usize| {
        let a: Vec<String> = (0..1000).map(|_| "2".to_string()).collect();
        let root: Vec<String> = (0..250).map(|_| "1".to_string()).collect();
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"children":[{}]}},{{"children":[{}]}},{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}},
{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":{}}}],
"buffers":[{{"uri":"tri.bin","byteLength":{}}}]}}"#,
            root.join(","),
            a.join(","),
            per_mesh * 3,
            per_mesh * 6,
            36 + per_mesh * 6
        )
    };
    let mut bin = triangle_bytes();
    bin.resize(36 + 200 * 6, 0);
    for t in 0..200 {
        bin[36 + t * 6..36 + t * 6 + 6].copy_from_slice(&[0, 0, 1, 0, 2, 0]);
    }
    std::fs::write(d.join("tri.bin"), &bin).unwrap();
    std::fs::write(d.join("limit.gltf"), instanced(200)).unwrap();
    let r = render(&d, "limit.gltf", &[]);
    refused(&r, &["limit.gltf", "50000000 triangles", "ground plane"]);
    assert!(r.secs < 5.0, "took {} s", r.secs);
}
