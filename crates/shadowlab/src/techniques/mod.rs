//! Shadow techniques: one module (or folder of stage modules) per algorithm, behind the
//! interface of [`technique`], and the registry that creates them by name.
//!
//! A technique gets a [`Frame`] — scene, camera, light and the shared camera pass — and
//! returns [`Shadows`]: a per-pixel RGB transmittance towards the light (1 = lit) and
//! [`Stats`].

pub mod adaptive;
pub mod alias_free;
pub mod cascaded;
pub mod convolution;
pub mod filtering;
pub mod lispsm;
pub mod moments;
pub mod pcss;
pub mod perspective;
pub mod raytrace;
pub mod shadow_map;
pub mod subpixel;
pub mod technique;
pub mod variance;

pub use crate::frame::{Frame, Stats, Visibility};
pub use technique::{
    check_range, find_param, in_key_order, not_read, param_text, param_value, parse_value,
    unknown_param, ParamRange, ParamSpec, ShadowTechnique, Shadows, BIAS, RESOLUTION, SLOPE_BIAS,
};

use crate::error::{Error, Result};

/// Every technique name, in the order reports list them.
pub const ALL: &[&str] = &[
    "raytrace", "sm", "pcf", "psm", "asm", "afsm", "subpixel", "csm", "vsm", "evsm", "msm",
    "cascaded", "lispsm", "pcss",
];

/// The soft variants of the filtered maps: `vsm`, `evsm`, `msm` and `csm` with `soft=true`
/// (each pixel's filter sized by a blocker search under the area light). They share
/// their base technique's parameter table.
pub const SOFT_VARIANTS: &[&str] = &["vsm-soft", "evsm-soft", "msm-soft", "csm-soft"];

/// The exact soft technique: `afsm` with an area light's light samples (equal to the soft
/// reference). Not in the default set.
pub const EXACT_SOFT: &str = "afsm-soft";

/// Techniques that live in crates above the library (the GPU crate's `gpu:` names): every
/// name starting with `prefix` goes to `create`, and `names` lists them for error messages.
/// The program that links such a crate registers it once at start (see [`register`]), so
/// every place that names a technique through [`create`] accepts its names.
#[derive(Clone, Copy, Debug)]
pub struct Extension {
    /// The names' common prefix, such as `gpu:`.
    pub prefix: &'static str,
    /// Every name it creates.
    pub names: &'static [&'static str],
    /// Creates one of them by name, with default parameters.
    pub create: fn(&str) -> Result<Box<dyn ShadowTechnique>>,
}

static EXTENSIONS: std::sync::RwLock<Vec<Extension>> = std::sync::RwLock::new(Vec::new());

/// Registers `ext`; a second registration of the same prefix replaces the first.
pub fn register(ext: Extension) {
    let mut all = EXTENSIONS.write().unwrap_or_else(|e| e.into_inner());
    all.retain(|e| e.prefix != ext.prefix);
    all.push(ext);
}

/// The registered extensions, in the order they were registered.
pub fn extensions() -> Vec<Extension> {
    EXTENSIONS.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// The technique names a list names (its items may be comma-separated lists), in report
/// order: `all` stands for [`ALL`] and `PREFIXall` (`gpu:all`) for every name of the
/// registered extension with that prefix; other names stand for themselves, as often as
/// they are listed. When a name and an extension's twin of it (`sm` and `gpu:sm`) are both
/// listed, the twin is moved right after the name, so tables and reports show each pair
/// side by side; the result is the expanded list reordered, nothing added or dropped.
pub fn expand_names<S: AsRef<str>>(list: &[S]) -> Vec<String> {
    let exts = extensions();
    let mut names: Vec<String> = Vec::new();
    for item in list.iter().flat_map(|s| s.as_ref().split(',')) {
        let item = item.trim();
        if item == "all" {
            names.extend(ALL.iter().map(|s| s.to_string()));
        } else if let Some(e) = exts.iter().find(|e| item == format!("{}all", e.prefix)) {
            names.extend(e.names.iter().map(|s| s.to_string()));
        } else if !item.is_empty() {
            names.push(item.to_string());
        }
    }
    let is_twin = |n: &str| {
        exts.iter()
            .filter_map(|e| n.strip_prefix(e.prefix))
            .any(|base| names.iter().any(|x| x == base))
    };
    let mut used = vec![false; names.len()];
    let mut out = Vec::with_capacity(names.len());
    for i in 0..names.len() {
        if used[i] || is_twin(&names[i]) {
            continue;
        }
        used[i] = true;
        out.push(names[i].clone());
        for e in &exts {
            let twin = format!("{}{}", e.prefix, names[i]);
            if let Some(j) = (0..names.len()).find(|&j| !used[j] && names[j] == twin) {
                used[j] = true;
                out.push(twin);
            }
        }
    }
    // Twins listed more often than their names keep their order at the end.
    out.extend(
        (0..names.len())
            .filter(|&j| !used[j])
            .map(|j| names[j].clone()),
    );
    out
}

/// A technique by name, with default parameters.
pub fn create(name: &str) -> Result<Box<dyn ShadowTechnique>> {
    if let Some(ext) = extensions()
        .into_iter()
        .find(|e| name.starts_with(e.prefix))
    {
        return (ext.create)(name);
    }
    Ok(match name {
        "raytrace" => Box::new(raytrace::RayTrace::default()),
        "sm" => Box::new(shadow_map::ShadowMap::standard()),
        "pcf" => Box::new(shadow_map::ShadowMap::pcf()),
        "psm" => Box::new(perspective::Perspective::default()),
        "asm" => Box::new(adaptive::Adaptive::default()),
        "afsm" => Box::new(alias_free::AliasFree::default()),
        "subpixel" => Box::new(subpixel::Subpixel::default()),
        "csm" | "convolution" => Box::new(convolution::Convolution::default()),
        "vsm" => Box::new(variance::Variance::default()),
        "evsm" => Box::new(moments::evsm::ExponentialVariance::default()),
        "msm" => Box::new(moments::msm::MomentShadowMap::default()),
        "cascaded" => Box::new(cascaded::Cascaded::default()),
        "lispsm" => Box::new(lispsm::LightSpacePerspective::default()),
        "pcss" => Box::new(pcss::Pcss::default()),
        EXACT_SOFT => Box::new(alias_free::soft::SoftAliasFree::default()),
        // The soft filtered variants: the same techniques with `soft=true`.
        "vsm-soft" | "evsm-soft" | "msm-soft" | "csm-soft" => {
            let mut t = create(name.trim_end_matches("-soft"))?;
            t.set_param("soft", "true")?;
            t
        }
        _ => {
            let more: String = extensions()
                .iter()
                .flat_map(|e| e.names.iter().map(|n| format!(", {n}")))
                .collect();
            return Err(Error::param(format!(
                "unknown technique {name:?}: known techniques are {}, {}, {EXACT_SOFT}{more}",
                ALL.join(", "),
                SOFT_VARIANTS.join(", ")
            )));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::technique::tests::significant_digits;
    use super::*;

    #[test]
    fn a_list_expands_all_and_puts_each_twin_after_its_name() {
        fn made(name: &str) -> Result<Box<dyn ShadowTechnique>> {
            create(name.trim_start_matches("twin:"))
        }
        register(Extension {
            prefix: "twin:",
            names: &["twin:psm", "twin:sm", "twin:only"],
            create: made,
        });
        let names = expand_names(&["twin:all", "sm,", "all"]);
        assert_eq!(names.len(), ALL.len() + 4, "{names:?}");
        let at = |n: &str| names.iter().position(|x| x == n).unwrap();
        assert_eq!(at("twin:sm"), at("sm") + 1);
        assert_eq!(at("twin:psm"), at("psm") + 1);
        // A twin without its CPU name keeps its place; the CPU names keep their order,
        // each as often as listed.
        assert_eq!(at("twin:only"), 0);
        assert_eq!(names.iter().filter(|n| *n == "sm").count(), 2);
        assert!(at("sm") < at("raytrace") && at("psm") < at("pcss"));
        assert_eq!(expand_names(&["pcf", " sm "]), ["pcf", "sm"]);
        assert_eq!(
            expand_names(&["twin:sm", "twin:sm", "sm"]),
            ["sm", "twin:sm", "twin:sm"]
        );
    }

    /// The parameter table is what `set_param` validates against and what the command line
    /// lists: it must name exactly the parameters `params` reports, in the same order, and
    /// accept every default.
    #[test]
    fn every_technique_has_a_table_that_matches_its_parameters() {
        for name in ALL.iter().chain(&[EXACT_SOFT]) {
            let mut t = create(name).unwrap();
            let table = t.param_specs();
            let params = t.params();
            let keys: Vec<&str> = table.iter().map(|s| s.key).collect();
            let names: Vec<&str> = params.keys().map(String::as_str).collect();
            assert_eq!(keys, names, "{name}: table keys vs params()");
            for spec in &table {
                assert!(!spec.meaning.is_empty(), "{name}.{}: no meaning", spec.key);
                let default = &params[spec.key];
                if default.is_null() {
                    continue; // an optional parameter that is unset by default
                }
                let text = param_text(default);
                t.set_param(spec.key, &text)
                    .unwrap_or_else(|e| panic!("{name}.{}: default {text} refused: {e}", spec.key));
                assert_eq!(&t.params()[spec.key], default, "{name}.{}", spec.key);
                let before = t.params();
                for bad in outside(spec.range) {
                    assert!(
                        t.set_param(spec.key, &bad).is_err(),
                        "{name}.{} = {bad} is outside {} but accepted",
                        spec.key,
                        spec.range
                    );
                    assert_eq!(t.params(), before, "{name}.{} = {bad} changed it", spec.key);
                }
            }
            let e = t.set_param("no-such-key", "1").unwrap_err().to_string();
            for spec in &table {
                assert!(
                    e.contains(spec.key),
                    "{name}: {e:?} does not list {}",
                    spec.key
                );
            }
        }
    }

    /// Every parameter's default, as the tables show it (`param_text`) and as
    /// `metrics.json` records it (the JSON of `params()`), has no more digits than the
    /// shortest decimal that reads back as the technique's `f32` (Rust's `{}` of that
    /// `f32`); and that text, set back, gives the same `params()` value bit for bit.
    /// (`param_value` is one-to-one on `f32`s, so the same value means the same `f32`.)
    #[test]
    fn every_default_prints_in_its_shortest_form_and_reads_back_bit_for_bit() {
        let names = ALL.iter().chain(SOFT_VARIANTS).chain(&[EXACT_SOFT]);
        let mut reals = 0;
        for name in names {
            let mut t = create(name).unwrap();
            let params = t.params();
            for spec in t.param_specs() {
                let default = &params[spec.key];
                let (text, json) = (param_text(default), default.to_string());
                let what = format!("{name}.{} = {text} (JSON {json})", spec.key);
                if let (ParamRange::Real(..), Some(x)) = (spec.range, default.as_f64()) {
                    reals += 1;
                    let used: f32 = text.parse().unwrap();
                    let shortest = used.to_string();
                    assert!(
                        significant_digits(&text) <= significant_digits(&shortest),
                        "{what} has more digits than {shortest}"
                    );
                    assert!(
                        significant_digits(&json) <= significant_digits(&shortest),
                        "{what}: its JSON has more digits than {shortest}"
                    );
                    assert_eq!((x as f32).to_bits(), used.to_bits(), "{what}");
                }
                if default.is_number() && !matches!(spec.range, ParamRange::Real(..)) {
                    assert!(!text.contains(['.', 'e']), "{what}: an integer");
                }
                if default.is_null() {
                    continue;
                }
                t.set_param(spec.key, &text).unwrap();
                let back = &t.params()[spec.key];
                assert_eq!(back, default, "{what} set back");
                if let (Some(a), Some(b)) = (back.as_f64(), default.as_f64()) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{what} set back");
                }
            }
        }
        assert!(reals > 40, "only {reals} real parameters walked");
    }

    /// Values just outside `range`, each of which the table must refuse.
    fn outside(range: ParamRange) -> Vec<String> {
        match range {
            ParamRange::Int(lo, hi) => vec![(lo - 1).to_string(), (hi + 1).to_string()],
            ParamRange::Real(lo, hi) => vec![
                (lo - 1.0 - lo.abs()).to_string(),
                (hi + 1.0 + hi.abs()).to_string(),
                "NaN".into(),
            ],
            ParamRange::Flag => vec!["maybe".into()],
            ParamRange::Choice(_) => vec!["no-such-word".into()],
        }
    }

    #[test]
    fn a_spec_checks_kind_and_range() {
        let spec = ParamSpec::int("n", 1, 8, "a count");
        assert_eq!(spec.u32("t", "8").unwrap(), 8);
        assert!(spec
            .u32("t", "9")
            .unwrap_err()
            .to_string()
            .contains("1..=8"));
        assert!(spec.u32("t", "x").is_err());
        assert!(spec.f32("t", "1").is_err());
        let words = ParamSpec::choice("w", &["a", "b"], "a word");
        assert_eq!(words.word("t", " b ").unwrap(), "b");
        assert!(words
            .word("t", "c")
            .unwrap_err()
            .to_string()
            .contains("a, b"));
        assert_eq!(
            ParamSpec::real("r", 0.0, 1.0, "x").f32("t", "0.5").unwrap(),
            0.5
        );
        assert!(ParamSpec::flag("f", "x").bool("t", "true").unwrap());
    }
}
