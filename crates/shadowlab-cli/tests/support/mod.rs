//! What the command line's integration tests share: the binary, the meshes the library
//! carries, a fresh folder per test, runs captured (under limits and a clock where a test
//! asks), the checks every refusal and success must pass, JSON read back, and image
//! comparisons that leave an error image behind when they fail.

// Each test file uses the part it needs.
#![allow(dead_code)]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

/// The `shadowlab` binary under test.
pub const SHADOWLAB: &str = env!("CARGO_BIN_EXE_shadowlab");

/// `shadowlab` with no arguments yet, given a private runtime folder so the Vulkan
/// loader's and the window system's probes print nothing (a bare machine sets no
/// `XDG_RUNTIME_DIR`, and lavapipe then says so on stderr beside the one sentence a test
/// reads).
pub fn shadowlab() -> Command {
    let runtime = std::env::temp_dir().join(format!(
        "shadowlab-{}-{}-runtime",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    if std::fs::create_dir_all(&runtime).is_ok() {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700));
    }
    let mut c = Command::new(SHADOWLAB);
    c.env("XDG_RUNTIME_DIR", &runtime);
    c
}

/// `shadowlab --quiet`: no progress bars or status lines.
pub fn quiet() -> Command {
    let mut c = shadowlab();
    c.arg("--quiet");
    c
}

/// A file the library carries under `crates/shadowlab/assets`.
pub fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shadowlab/assets")).join(name)
}

/// A fresh, empty folder for one test, named after the test file, this process and
/// `name`.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "shadowlab-{}-{}-{name}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A finished run: its exit status (none when a signal ended it), what it printed, and
/// how long it took.
pub struct Ran {
    /// The exit status.
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
    /// Wall time in seconds.
    pub secs: f64,
}

impl Ran {
    /// True when the run exited with 0.
    pub fn success(&self) -> bool {
        self.code == Some(0)
    }
}

/// A command run to the end with what it prints captured: `quiet().arg("scenes").ran()`.
pub trait Capture {
    /// Runs the command, capturing its output.
    fn ran(&mut self) -> Ran;
}

impl Capture for Command {
    fn ran(&mut self) -> Ran {
        let t0 = Instant::now();
        let out: Output = self.output().expect("the shadowlab binary runs");
        Ran {
            code: out.status.code(),
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
            secs: t0.elapsed().as_secs_f64(),
        }
    }
}

/// Runs `cmd` (its standard streams already set), killing it past `limit`, which fails
/// the test; returns its status and wall time.
pub fn wait_at_most(cmd: &mut Command, limit: Duration) -> (ExitStatus, f64) {
    let t0 = Instant::now();
    let mut child = cmd.spawn().expect("the command starts");
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return (s, t0.elapsed().as_secs_f64());
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} ran past {limit:?} (killed)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs `shadowlab --quiet ARGS` in `dir` under the shell limits `ulimits` (e.g.
/// `"ulimit -v 4000000"`), killing it past `limit`; standard output is dropped.
pub fn run_limited(dir: &Path, ulimits: &str, limit: Duration, args: &[&str]) -> Ran {
    let err_path = dir.join(".stderr");
    let err = std::fs::File::create(&err_path).unwrap();
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("{ulimits}; exec \"$0\" \"$@\""))
        .arg(SHADOWLAB)
        .arg("--quiet")
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(err);
    let (status, secs) = wait_at_most(&mut cmd, limit);
    let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
    let _ = std::fs::remove_file(&err_path);
    Ran {
        code: status.code(),
        stdout: String::new(),
        stderr,
        secs,
    }
}

/// One sentence on stderr that starts with `error:`, mentions every one of `needles`
/// and is no panic; the exit status `code`.
pub fn failed_with(r: &Ran, code: i32, needles: &[&str]) {
    let e = &r.stderr;
    assert_eq!(
        r.code,
        Some(code),
        "expected exit {code}, got {:?}: {e}",
        r.code
    );
    assert!(!e.contains("panicked"), "panic: {e}");
    assert_eq!(e.trim().lines().count(), 1, "expected one sentence: {e}");
    assert!(e.starts_with("error: "), "{e}");
    for n in needles {
        assert!(
            e.to_lowercase().contains(&n.to_lowercase()),
            "{e:?} does not mention {n:?}"
        );
    }
}

/// Bad input: exit status 2 and one sentence mentioning every one of `needles`.
pub fn refused(r: &Ran, needles: &[&str]) {
    failed_with(r, 2, needles);
}

/// Success, or the stderr of the failure.
pub fn ok(r: &Ran) {
    assert_eq!(r.code, Some(0), "expected success: {}", r.stderr);
}

/// Runs `cmd` and checks it succeeded.
pub fn run_ok(cmd: &mut Command) -> Ran {
    let r = cmd.ran();
    ok(&r);
    r
}

/// A JSON file.
pub fn read_json(p: &Path) -> Value {
    let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The `metrics.json` of the report in `dir`.
pub fn metrics(dir: &Path) -> Value {
    read_json(&dir.join("metrics.json"))
}

/// `[x, y, z]` of a JSON record.
pub fn xyz(v: &Value) -> [f32; 3] {
    let a: Vec<f32> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    [a[0], a[1], a[2]]
}

/// Where image comparisons that fail leave their error images: `target/test-failures/`.
pub fn failures_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("the target folder")
        .join("test-failures");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The error image of two RGB images of `width × height` pixels (`[r, g, b]` in 0–1 each,
/// row-major from the top): black where they agree, red where `a` is lighter, blue where
/// it is darker, brighter for larger differences (√ of the largest channel difference).
pub fn error_image(width: u32, height: u32, a: &[[f32; 3]], b: &[[f32; 3]]) -> image::RgbImage {
    image::RgbImage::from_fn(width, height, |x, y| {
        let k = (y * width + x) as usize;
        let d: Vec<f32> = (0..3).map(|c| a[k][c] - b[k][c]).collect();
        let big = d
            .iter()
            .copied()
            .fold(0.0f32, |m, v| if v.abs() > m.abs() { v } else { m });
        let v = (big.abs().sqrt().min(1.0) * 255.0) as u8;
        if big > 0.0 {
            image::Rgb([v, 0, 0])
        } else {
            image::Rgb([0, 0, v])
        }
    })
}

/// Asserts two RGB images are equal pixel for pixel; when they are not, writes their
/// error image into [`failures_dir`] as `<what>.png` and names it in the failure.
pub fn assert_same_pixels(what: &str, width: u32, height: u32, a: &[[f32; 3]], b: &[[f32; 3]]) {
    assert_eq!(a.len(), b.len(), "{what}: the images differ in size");
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    if differ == 0 {
        return;
    }
    let first = a.iter().zip(b).position(|(x, y)| x != y).unwrap();
    let path = failures_dir().join(format!("{}.png", file_name(what)));
    error_image(width, height, a, b)
        .save(&path)
        .unwrap_or_else(|e| {
            panic!(
                "{what}: {differ} pixels differ; cannot write {}: {e}",
                path.display()
            )
        });
    eprintln!("{what}: error image in {}", path.display());
    panic!(
        "{what}: {differ} of {} pixels differ (the first, pixel {first}: {:?} against {:?}); error image: {}",
        a.len(),
        a[first],
        b[first],
        path.display()
    );
}

/// Asserts two files hold the same bytes; when they do not and both are images, writes
/// their error image into [`failures_dir`] and names it in the failure.
pub fn assert_same_files(what: &str, a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    if x == y {
        return;
    }
    if let (Ok(p), Ok(q)) = (image::open(a), image::open(b)) {
        let (p, q) = (p.to_rgb32f(), q.to_rgb32f());
        if p.dimensions() == q.dimensions() {
            let px = |i: &image::Rgb32FImage| i.pixels().map(|p| p.0).collect::<Vec<_>>();
            assert_same_pixels(what, p.width(), p.height(), &px(&p), &px(&q));
        }
    }
    panic!("{what}: {} and {} differ", a.display(), b.display());
}

/// `what` as a file name.
fn file_name(what: &str) -> String {
    what.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
