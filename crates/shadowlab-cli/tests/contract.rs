//! `docs/CLI.md` is the command-line contract: every command, flag, bench suite and JSON
//! field the program has is documented there, and everything documented there exists.

mod support;

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use support::{read_json, shadowlab, tmp, Capture, Ran};

const CLI_MD: &str = include_str!("../../../docs/CLI.md");

fn run(args: &[&str]) -> Ran {
    shadowlab().args(args).ran()
}

/// The lines of the section that starts with the heading `heading`, up to the next heading
/// of the same or a higher level.
fn section(heading: &str) -> Vec<&'static str> {
    let level = heading.chars().take_while(|&c| c == '#').count();
    let mut lines = CLI_MD.lines();
    lines
        .by_ref()
        .find(|l| l.trim() == heading)
        .unwrap_or_else(|| panic!("docs/CLI.md has no section {heading:?}"));
    lines
        .take_while(|l| {
            let h = l.chars().take_while(|&c| c == '#').count();
            h == 0 || h > level
        })
        .collect()
}

/// The first cell of each row of the tables in `lines` (header and rule rows skipped).
fn first_cells(lines: &[&'static str]) -> Vec<&'static str> {
    table_rows(lines).into_iter().map(|r| r[0]).collect()
}

fn table_rows(lines: &[&'static str]) -> Vec<Vec<&'static str>> {
    let rows: Vec<Vec<&str>> = lines
        .iter()
        .filter(|l| l.trim_start().starts_with('|'))
        .map(|l| {
            // Split on cell bars, not on escaped `\|` inside a cell.
            let mut cells = Vec::new();
            let body = l.trim().trim_start_matches('|');
            let mut start = 0;
            let bytes = body.as_bytes();
            for i in 0..bytes.len() {
                if bytes[i] == b'|' && (i == 0 || bytes[i - 1] != b'\\') {
                    cells.push(body[start..i].trim());
                    start = i + 1;
                }
            }
            cells
        })
        .collect();
    // The first row is the header, the second the rule.
    rows.into_iter().skip(2).collect()
}

/// Every `--flag` named in `text`.
fn flags_in(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i + 2 < b.len() {
        if b[i] == b'-' && b[i + 1] == b'-' && (i == 0 || !b[i - 1].is_ascii_alphanumeric()) {
            let s = i + 2;
            let mut e = s;
            while e < b.len() && (b[e].is_ascii_alphanumeric() || b[e] == b'-') {
                e += 1;
            }
            if e > s && b[s].is_ascii_alphabetic() {
                out.insert(format!("--{}", &text[s..e]));
            }
            i = e;
        } else {
            i += 1;
        }
    }
    out
}

/// The long flags `shadowlab <cmd> --help` lists, without clap's own `--help`/`--version`.
fn parser_flags(cmd: &str) -> BTreeSet<String> {
    let out = run(&[cmd, "--help"]);
    assert!(out.success(), "{cmd} --help failed");
    let help = &out.stdout;
    let mut flags = BTreeSet::new();
    for line in help.lines() {
        let t = line.trim_start();
        let t = match t.strip_prefix('-') {
            Some(rest) if !rest.starts_with('-') => rest.split_once(", ").map_or(t, |(_, r)| r),
            _ => t,
        };
        if let Some(rest) = t.strip_prefix("--") {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            if name != "help" && name != "version" {
                flags.insert(format!("--{name}"));
            }
        }
    }
    flags
}

fn documented_flags(headings: &[&str]) -> BTreeSet<String> {
    headings
        .iter()
        .flat_map(|h| first_cells(&section(h)))
        .flat_map(flags_in)
        .collect()
}

fn assert_same(what: &str, parser: &BTreeSet<String>, doc: &BTreeSet<String>) {
    let missing: Vec<_> = parser.difference(doc).collect();
    let stale: Vec<_> = doc.difference(parser).collect();
    assert!(
        missing.is_empty() && stale.is_empty(),
        "{what}: in the program but not in docs/CLI.md: {missing:?}; in docs/CLI.md but not in the program: {stale:?}"
    );
}

#[test]
fn every_flag_is_documented_and_every_documented_flag_exists() {
    let global = "### Flags of every command";
    let scene = "### Scene flags (`render` and `compare`)";
    assert_same(
        "render",
        &parser_flags("render"),
        &documented_flags(&[global, scene, "### `render`"]),
    );
    assert_same(
        "compare",
        &parser_flags("compare"),
        &documented_flags(&[global, scene, "### `compare`"]),
    );
    assert_same(
        "view",
        &parser_flags("view"),
        &documented_flags(&[global, scene, "### `view`"]),
    );
    assert_same(
        "bench",
        &parser_flags("bench"),
        &documented_flags(&[global, "### `bench`"]),
    );
}

#[test]
fn every_command_is_documented() {
    let out = run(&["--help"]);
    let help = &out.stdout;
    let commands: BTreeSet<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect();
    assert!(!commands.is_empty(), "no commands in --help: {help}");
    let documented: BTreeSet<String> = section("## Commands")
        .iter()
        .filter_map(|l| l.strip_prefix("shadowlab "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| !c.starts_with('#'))
        .map(str::to_string)
        .collect();
    assert_same("commands", &commands, &documented);
}

#[test]
fn every_bench_suite_is_documented() {
    let out = run(&["--quiet", "bench", "no-such-suite"]);
    assert_eq!(out.code, Some(2));
    let err = &out.stderr;
    let list = err
        .split("known suites are ")
        .nth(1)
        .unwrap_or_else(|| panic!("the error lists no suites: {err}"));
    let parser: BTreeSet<String> = list
        .trim()
        .split(", ")
        .map(|s| s.trim().to_string())
        .collect();
    let doc: BTreeSet<String> = first_cells(&section("## Bench suites"))
        .into_iter()
        // A row such as `engines --backend gpu` documents a variant of a suite: it names
        // the suite by its first word.
        .map(|c| {
            let cell = c.trim_matches('`');
            cell.split_whitespace().next().unwrap_or(cell).to_string()
        })
        .collect();
    assert_same("bench suites", &parser, &doc);
}

/// A documented JSON field.
struct Field {
    map: bool,
    always: bool,
}

/// The fields of the table in section `heading`, by path. A name `.x` after `a.b.c`
/// stands for `a.b.x`.
fn documented_fields(heading: &str) -> BTreeMap<String, Field> {
    let mut out = BTreeMap::new();
    for row in table_rows(&section(heading)) {
        let mut prefix = String::new();
        for name in row[0].split(',') {
            let name = name.trim().trim_matches('`');
            let path = if let Some(rest) = name.strip_prefix('.') {
                format!("{prefix}.{rest}")
            } else {
                prefix = name.rsplit_once('.').map_or("", |(p, _)| p).to_string();
                name.to_string()
            };
            out.insert(
                path,
                Field {
                    map: row[1].contains("map"),
                    always: row[2] == "always",
                },
            );
        }
    }
    out
}

/// Every field path in `v`, not descending into documented maps.
fn paths(v: &Value, prefix: &str, doc: &BTreeMap<String, Field>, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                out.insert(p.clone());
                if !doc.get(&p).is_some_and(|f| f.map) {
                    paths(x, &p, doc, out);
                }
            }
        }
        Value::Array(a) => {
            for x in a {
                paths(x, &format!("{prefix}[]"), doc, out);
            }
        }
        _ => {}
    }
}

/// Every field of `outputs` documented in `heading`; every field documented as always
/// present there in `plain`.
fn check_fields(heading: &str, plain: &Value, outputs: &[Value]) {
    let doc = documented_fields(heading);
    let mut seen = BTreeSet::new();
    for v in outputs {
        paths(v, "", &doc, &mut seen);
    }
    let undocumented: Vec<_> = seen.iter().filter(|p| !doc.contains_key(*p)).collect();
    assert!(
        undocumented.is_empty(),
        "{heading}: fields written but not documented in docs/CLI.md: {undocumented:?}"
    );
    let mut in_plain = BTreeSet::new();
    paths(plain, "", &doc, &mut in_plain);
    let absent: Vec<_> = doc
        .iter()
        .filter(|(p, f)| f.always && !in_plain.contains(*p))
        .map(|(p, _)| p)
        .collect();
    assert!(
        absent.is_empty(),
        "{heading}: documented as always present but not written: {absent:?}"
    );
}

#[test]
fn every_metrics_field_is_documented_and_every_always_field_is_written() {
    let d = tmp("metrics");
    let size = ["--width", "64", "--height", "48"];
    let mut outputs = Vec::new();
    let variants: [&[&str]; 4] = [
        &["--scene", "room", "--techniques", "all"],
        &[
            "--scene",
            "penumbra",
            "--techniques",
            "sm,pcf",
            "--light-samples",
            "16",
        ],
        &[
            "--scene",
            "room",
            "--techniques",
            "sm,asm",
            "--frames",
            "2",
            "--dump",
            "--sweep",
            "sm.resolution=256,512",
        ],
        &[
            "--scene",
            "hairball",
            "--scene-param",
            "hairs=20",
            "--techniques",
            "afsm",
            "--layers",
        ],
    ];
    for (i, extra) in variants.iter().enumerate() {
        let out_dir = d.join(format!("r{i}"));
        let mut args = vec!["--quiet", "compare", "--out", out_dir.to_str().unwrap()];
        args.extend_from_slice(&size);
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(out.success(), "compare {extra:?}: {}", out.stderr);
        outputs.push(read_json(&out_dir.join("metrics.json")));
    }
    check_fields("## metrics.json (compare)", &outputs[0], &outputs);
}

#[test]
fn every_stats_field_is_documented_and_every_always_field_is_written() {
    let d = tmp("stats");
    let mut outputs = Vec::new();
    let variants: [&[&str]; 4] = [
        &["--scene", "room", "--technique", "sm"],
        &[
            "--scene",
            "penumbra",
            "--technique",
            "sm",
            "--light-samples",
            "16",
        ],
        &["--scene", "room", "--technique", "asm", "--frames", "2"],
        &[
            "--scene",
            "hairball",
            "--scene-param",
            "hairs=20",
            "--technique",
            "afsm",
            "--layers",
        ],
    ];
    for (i, extra) in variants.iter().enumerate() {
        let stats = d.join(format!("s{i}.json"));
        let png = d.join(format!("s{i}.png"));
        let mut args = vec![
            "--quiet",
            "render",
            "--width",
            "64",
            "--height",
            "48",
            "--output",
            png.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(out.success(), "render {extra:?}: {}", out.stderr);
        outputs.push(read_json(&stats));
    }
    check_fields("## render --stats", &outputs[0], &outputs);
}
