//! The interface every shadow algorithm implements, what it returns, and the table of
//! parameters each one validates its settings against.
//!
//! Techniques are `&mut self` so progressive ones keep state between frames. All of them
//! share [`crate::light::Light::illuminates`]: a pixel whose viewed side faces away from
//! the light, or lies outside a spot light's cone, is unlit (0) in every technique and in
//! the reference alike.

use crate::error::{Error, Result};
use crate::frame::{Frame, Stats, Visibility};
use crate::math::Vec3;
use crate::raster::MAX_RASTER_SIDE;
use std::collections::BTreeMap;

/// The result of one technique on one frame.
#[derive(Clone, Debug)]
pub struct Shadows {
    /// The shadow term.
    pub visibility: Visibility,
    /// Timings, memory and counters.
    pub stats: Stats,
    /// The shadow term of every layer sample of [`Frame::layers`], in its order; `None`
    /// when the frame has no layers or the technique shades only the nearest surface.
    pub layers: Option<Vec<Vec3>>,
}

impl Shadows {
    /// The result of a technique that shades the nearest surface of each pixel of `frame`
    /// with the shadow term `value` (one per pixel, row-major).
    pub fn of_frame(frame: &Frame, value: Vec<Vec3>, stats: Stats) -> Self {
        Shadows::new(
            Visibility {
                width: frame.view.width,
                height: frame.view.height,
                value,
            },
            stats,
        )
    }

    /// The result of a technique that shades the nearest surface of each pixel only.
    pub fn new(visibility: Visibility, stats: Stats) -> Self {
        Shadows {
            visibility,
            stats,
            layers: None,
        }
    }
}

/// A shadow algorithm.
pub trait ShadowTechnique: Send {
    /// The technique's name as the command line spells it (`sm`, `afsm`, …).
    fn name(&self) -> &'static str;
    /// Every parameter in effect, defaults included.
    fn params(&self) -> BTreeMap<String, serde_json::Value>;
    /// Every parameter's key, range and meaning, in the order [`ShadowTechnique::params`]
    /// lists them: the table [`ShadowTechnique::set_param`] validates against.
    fn param_specs(&self) -> Vec<ParamSpec>;
    /// Sets one parameter from its text form; unknown keys and bad values are errors
    /// that list what is accepted.
    fn set_param(&mut self, key: &str, value: &str) -> Result<()>;
    /// Computes the shadow term of a frame.
    fn render(&mut self, frame: &Frame) -> Result<Shadows>;
    /// For a progressive technique (one that refines its result over the frames of a still
    /// view): `Some(true)` once another frame of the same view would change nothing,
    /// `Some(false)` while it is still refining. `None` for techniques that are done in one
    /// frame.
    fn converged(&self) -> Option<bool> {
        None
    }
}

/// A real parameter's value as [`ShadowTechnique::params`] lists it: the number whose
/// shortest decimal is the shortest decimal that reads back as `v` (`0.0005`, not the
/// `0.0005000000237487257` that widening `v` to `f64` gives).
///
/// Every technique, in this crate or another, builds the value of each `f32` parameter
/// with this function (never `serde_json::Value::from(f32)`), so that the listing, the
/// reports, `metrics.json` and Python all show the value as a person would write it, and
/// that text given back to [`ShadowTechnique::set_param`] sets the same `f32`, bit for
/// bit. (The shortest decimal of an `f32` has at most 9 digits, so the `f64` nearest to
/// it prints as that same decimal.) Integers, words and `f64` parameters need nothing of
/// the kind: their JSON form is already their shortest. [`param_text`] prints any value.
pub fn param_value(v: f32) -> serde_json::Value {
    let shortest: f64 = v.to_string().parse().unwrap_or(f64::from(v));
    serde_json::Value::from(shortest)
}

/// A parameter value as text, the way `--param KEY=VALUE` takes it and every table shows
/// it: words without quotes, numbers in their shortest form without a bare `.0`
/// (`0.0005`, `16`, `512`, `true`).
pub fn param_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => {
            let t = n.to_string();
            match t.strip_suffix(".0") {
                Some(whole) => whole.to_string(),
                None => t,
            }
        }
        other => other.to_string(),
    }
}

/// The values a technique parameter accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamRange {
    /// An integer in `lo..=hi`.
    Int(i64, i64),
    /// A real number in `lo..=hi`.
    Real(f64, f64),
    /// `true` or `false`.
    Flag,
    /// One of these words.
    Choice(&'static [&'static str]),
}

impl std::fmt::Display for ParamRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamRange::Int(lo, hi) => write!(f, "{lo}..={hi}"),
            ParamRange::Real(lo, hi) => write!(f, "{lo}..={hi}"),
            ParamRange::Flag => write!(f, "true|false"),
            ParamRange::Choice(words) => write!(f, "{}", words.join("|")),
        }
    }
}

/// One parameter of a technique: its key on the command line, the values it accepts and
/// what it means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// The key, as `--param KEY=VALUE` spells it.
    pub key: &'static str,
    /// The values it accepts.
    pub range: ParamRange,
    /// One line of meaning.
    pub meaning: &'static str,
}

impl ParamSpec {
    /// An integer parameter in `lo..=hi`.
    pub const fn int(key: &'static str, lo: i64, hi: i64, meaning: &'static str) -> Self {
        ParamSpec {
            key,
            range: ParamRange::Int(lo, hi),
            meaning,
        }
    }

    /// A real parameter in `lo..=hi`.
    pub const fn real(key: &'static str, lo: f64, hi: f64, meaning: &'static str) -> Self {
        ParamSpec {
            key,
            range: ParamRange::Real(lo, hi),
            meaning,
        }
    }

    /// A `true`/`false` parameter.
    pub const fn flag(key: &'static str, meaning: &'static str) -> Self {
        ParamSpec {
            key,
            range: ParamRange::Flag,
            meaning,
        }
    }

    /// A parameter taking one of `words`.
    pub const fn choice(
        key: &'static str,
        words: &'static [&'static str],
        meaning: &'static str,
    ) -> Self {
        ParamSpec {
            key,
            range: ParamRange::Choice(words),
            meaning,
        }
    }

    fn int_in<T>(&self, technique: &str, value: &str) -> Result<T>
    where
        T: std::str::FromStr + Copy + std::fmt::Display + TryFrom<i64> + Into<i128>,
    {
        let v: T = parse_value(technique, self.key, value)?;
        match self.range {
            ParamRange::Int(lo, hi) => {
                let x: i128 = v.into();
                if x >= lo as i128 && x <= hi as i128 {
                    Ok(v)
                } else {
                    Err(out_of_range(technique, self.key, v, lo, hi))
                }
            }
            _ => Err(self.wrong_kind(technique, "an integer")),
        }
    }

    /// Parses an integer parameter as `u32`, checking its range.
    pub fn u32(&self, technique: &str, value: &str) -> Result<u32> {
        self.int_in(technique, value)
    }

    /// Parses an integer parameter as `usize`, checking its range.
    pub fn usize(&self, technique: &str, value: &str) -> Result<usize> {
        self.int_in::<u64>(technique, value).map(|v| v as usize)
    }

    /// Parses a real parameter as `f32`, checking its range.
    pub fn f32(&self, technique: &str, value: &str) -> Result<f32> {
        let v: f32 = parse_value(technique, self.key, value)?;
        match self.range {
            ParamRange::Real(lo, hi) => check_range(technique, self.key, v, lo as f32, hi as f32),
            _ => Err(self.wrong_kind(technique, "a real number")),
        }
    }

    /// Parses a `true`/`false` parameter.
    pub fn bool(&self, technique: &str, value: &str) -> Result<bool> {
        match self.range {
            ParamRange::Flag => parse_value(technique, self.key, value),
            _ => Err(self.wrong_kind(technique, "a flag")),
        }
    }

    /// Parses a parameter taking one of a list of words.
    pub fn word(&self, technique: &str, value: &str) -> Result<&'static str> {
        match self.range {
            ParamRange::Choice(words) => {
                let v = value.trim();
                words.iter().copied().find(|w| *w == v).ok_or_else(|| {
                    Error::param(format!(
                        "parameter {technique}.{} = {value:?} is not one of {}",
                        self.key,
                        words.join(", ")
                    ))
                })
            }
            _ => Err(self.wrong_kind(technique, "a word")),
        }
    }

    fn wrong_kind(&self, technique: &str, what: &str) -> Error {
        Error::Internal(format!(
            "parameter {technique}.{} is read as {what} but its table says {}",
            self.key, self.range
        ))
    }
}

/// The spec of `key` in `table`, or the error naming the technique's parameters.
pub fn find_param(technique: &str, table: &[ParamSpec], key: &str) -> Result<ParamSpec> {
    table.iter().find(|s| s.key == key).copied().ok_or_else(|| {
        let known: Vec<&str> = table.iter().map(|s| s.key).collect();
        unknown_param(technique, key, &known)
    })
}

/// The error for a key that is in a technique's table but that its `set_param` does not
/// read: a fault of the technique, not of the input.
pub fn not_read(technique: &str, key: &str) -> Error {
    Error::Internal(format!(
        "parameter {technique}.{key} is in its table but not read"
    ))
}

/// `table` in key order, the order [`ShadowTechnique::params`] lists the keys in.
pub fn in_key_order(mut table: Vec<ParamSpec>) -> Vec<ParamSpec> {
    table.sort_by_key(|s| s.key);
    table
}

/// The side of a square light-space map, in texels.
pub const RESOLUTION: ParamSpec = ParamSpec::int(
    "resolution",
    1,
    MAX_RASTER_SIDE as i64,
    "side of the shadow map in texels",
);
/// The constant depth bias, in texels of the map at the receiver.
pub const BIAS: ParamSpec = ParamSpec::real(
    "bias",
    0.0,
    1000.0,
    "constant depth bias in texels: larger detaches shadows (peter-panning), smaller gives acne",
);
/// The slope-scaled depth bias, in texels per unit of tan θ.
pub const SLOPE_BIAS: ParamSpec = ParamSpec::real(
    "slope-bias",
    0.0,
    1000.0,
    "depth bias in texels per unit of tan θ (θ: angle between normal and light): cures acne on slopes",
);

/// The error for an unknown parameter key of `technique`, listing the known keys.
pub fn unknown_param(technique: &str, key: &str, known: &[&str]) -> Error {
    Error::param(format!(
        "technique {technique} has no parameter {key:?}: its parameters are {}",
        known.join(", ")
    ))
}

/// Parses `value` for `technique.key`, naming both on failure.
pub fn parse_value<T: std::str::FromStr>(technique: &str, key: &str, value: &str) -> Result<T> {
    value.trim().parse::<T>().map_err(|_| {
        Error::param(format!(
            "parameter {technique}.{key} = {value:?} is not a valid {}",
            std::any::type_name::<T>()
        ))
    })
}

fn out_of_range(
    technique: &str,
    key: &str,
    value: impl std::fmt::Display,
    lo: impl std::fmt::Display,
    hi: impl std::fmt::Display,
) -> Error {
    Error::param(format!(
        "parameter {technique}.{key} = {value} is outside its range {lo}..={hi}"
    ))
}

/// Checks `value` lies in `lo..=hi` for `technique.key`.
pub fn check_range<T: PartialOrd + std::fmt::Display + Copy>(
    technique: &str,
    key: &str,
    value: T,
    lo: T,
    hi: T,
) -> Result<T> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(out_of_range(technique, key, value, lo, hi))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The significant digits of a decimal number's text (`0.00050` → 1, `3e-5` → 1,
    /// `16.0` → 2, `512` → 3).
    pub(crate) fn significant_digits(text: &str) -> usize {
        let mantissa = text.trim_start_matches('-').split(['e', 'E']).next();
        let digits: String = mantissa
            .unwrap_or("")
            .chars()
            .filter(|c| *c != '.')
            .collect();
        digits.trim_start_matches('0').trim_end_matches('0').len()
    }

    /// `param_value` over a spread of non-negative finite `f32`s across every binade
    /// (each 4099th bit pattern, subnormals included): the text it prints reads back as
    /// the same `f32`, with no more significant digits than Rust's shortest `{}` of the
    /// `f32`; the JSON number, narrowed as a reader of `metrics.json` would, is the same
    /// `f32`; and the values rise with the `f32`s, so no two share one.
    #[test]
    fn a_real_parameter_prints_its_shortest_decimal_and_reads_back_bit_for_bit() {
        let mut previous: Option<f64> = None;
        for bits in (0..0x7f80_0000_u32).step_by(4099) {
            let v = f32::from_bits(bits);
            let value = param_value(v);
            let x = value.as_f64().unwrap();
            let text = param_text(&value);
            let back: f32 = text.parse().unwrap();
            assert_eq!(back.to_bits(), bits, "{v:e} printed {text}");
            assert_eq!((x as f32).to_bits(), bits, "{v:e} recorded as {x:e}");
            let shortest = v.to_string();
            assert!(
                significant_digits(&text) <= significant_digits(&shortest),
                "{v:e}: {text} vs {shortest}"
            );
            assert!(
                previous.is_none_or(|p| p < x),
                "{v:e} not above the one before"
            );
            previous = Some(x);
        }
        for (v, text) in [
            (0.0005_f32, "0.0005"),
            (0.1, "0.1"),
            (3e-5, "0.00003"),
            (16.0, "16"),
        ] {
            assert_eq!(param_text(&param_value(v)), text);
        }
        assert_eq!(param_text(&serde_json::Value::from(512)), "512");
        assert_eq!(param_text(&serde_json::Value::from("auto")), "auto");
        assert_eq!(param_text(&serde_json::Value::from(true)), "true");
    }
}
