//! A bounded random-mutation loop over a kept corpus, for machines without `cargo fuzz`:
//! each round takes a corpus input, applies a few random edits (bit flips, byte and
//! number replacements, deletions, duplicated or spliced chunks) and runs it through the
//! target's harness; an input that panics is written to `fuzz/open/<target>/`.
//!
//! `cargo run --release -p shadowlab-fuzz --example mutate -- TARGET SECONDS [SEED]`
//! with TARGET one of obj, ply, gltf, toml, pipeline. Deterministic for a given seed
//! except for how many rounds fit in the time.

use shadowlab_fuzz::{load, pipeline, Format};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// xorshift64*: a small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Numbers that break naive length and index arithmetic.
const INTERESTING: &[&str] = &[
    "0",
    "-1",
    "1e38",
    "-3e38",
    "nan",
    "inf",
    "4294967295",
    "4294967296",
    "2147483648",
    "18446744073709551615",
    "65535",
    "255",
    "256",
    "1e-38",
    "100000000",
    "/dev/zero",
    "../",
    "%2e%2e/",
    "\"\"",
];

fn mutate(rng: &mut Rng, corpus: &[Vec<u8>], mut d: Vec<u8>) -> Vec<u8> {
    for _ in 0..1 + rng.below(4) {
        let len = d.len();
        match rng.below(7) {
            0 if len > 0 => {
                let i = rng.below(len);
                d[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                d[i] = rng.next() as u8;
            }
            2 if len > 0 => {
                let i = rng.below(len);
                let n = rng.below(16).min(len - i);
                d.drain(i..i + n);
            }
            3 if len > 0 => {
                let i = rng.below(len);
                let n = (1 + rng.below(64)).min(len - i);
                let chunk = d[i..i + n].to_vec();
                let at = rng.below(len + 1);
                let times = 1 + rng.below(8);
                for _ in 0..times {
                    d.splice(at..at, chunk.iter().copied());
                }
            }
            4 => {
                // Replace a run of digits (or insert) with an interesting number.
                let s = INTERESTING[rng.below(INTERESTING.len())].as_bytes();
                let at = rng.below(len + 1);
                let mut end = at;
                while end < d.len() && d[end].is_ascii_digit() {
                    end += 1;
                }
                d.splice(at..end, s.iter().copied());
            }
            5 if !corpus.is_empty() => {
                // Splice: our head, another input's tail.
                let other = &corpus[rng.below(corpus.len())];
                let cut = rng.below(len + 1);
                let from = rng.below(other.len() + 1);
                d.truncate(cut);
                d.extend_from_slice(&other[from..]);
            }
            _ => {
                let at = rng.below(len + 1);
                d.insert(at, rng.next() as u8);
            }
        }
    }
    // Keep inputs small, as libFuzzer's default -max_len does.
    d.truncate(1 << 16);
    d
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let target = args.get(1).map(String::as_str).unwrap_or("obj").to_string();
    let secs: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(60);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let run: fn(&[u8]) = match target.as_str() {
        "obj" => |d| load(Format::Obj, d),
        "ply" => |d| load(Format::Ply, d),
        "gltf" => |d| load(Format::Gltf, d),
        "toml" => |d| load(Format::Toml, d),
        "pipeline" => pipeline,
        other => {
            eprintln!("error: unknown target {other:?} (obj, ply, gltf, toml or pipeline)");
            std::process::exit(2);
        }
    };
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fuzz"));
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("corpus").join(&target))
        .map(|rd| rd.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    let corpus: Vec<Vec<u8>> = files.iter().filter_map(|p| std::fs::read(p).ok()).collect();
    if corpus.is_empty() {
        eprintln!("error: no corpus for {target}");
        std::process::exit(2);
    }
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let t0 = Instant::now();
    let (mut runs, mut findings) = (0u64, 0u64);
    let mut slowest = (Duration::ZERO, Vec::new());
    while t0.elapsed() < Duration::from_secs(secs) {
        let base = corpus[rng.below(corpus.len())].clone();
        let input = mutate(&mut rng, &corpus, base);
        let t = Instant::now();
        let r = std::panic::catch_unwind(|| run(&input));
        let took = t.elapsed();
        if took > slowest.0 {
            slowest = (took, input.clone());
        }
        runs += 1;
        if r.is_err() {
            findings += 1;
            let dir = root.join("open").join(&target);
            let _ = std::fs::create_dir_all(&dir);
            let _ = std::fs::write(dir.join(format!("mutate-{seed}-{runs}")), &input);
        }
    }
    println!(
        "{target}: {runs} runs in {} s, {findings} panics, slowest input {:.1} ms ({} bytes)",
        t0.elapsed().as_secs(),
        slowest.0.as_secs_f64() * 1e3,
        slowest.1.len()
    );
}
