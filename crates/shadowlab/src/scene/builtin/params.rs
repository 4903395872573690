//! A built-in scene's parameters (`--scene-param K=V`, as text), checked against the keys
//! the scene knows and each value against its range.

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// A scene's parameters, checked against the keys it knows.
pub(super) struct Params<'a> {
    scene: &'a str,
    pub(super) map: &'a BTreeMap<String, String>,
}

impl<'a> Params<'a> {
    /// Fails on any key not in `known`, naming it and listing the known keys.
    pub(super) fn new(
        scene: &'a str,
        map: &'a BTreeMap<String, String>,
        known: &[&str],
    ) -> Result<Self> {
        if let Some(k) = map.keys().find(|k| !known.contains(&k.as_str())) {
            let list = if known.is_empty() {
                "it has no parameters".to_string()
            } else {
                format!("known parameters: {}", known.join(", "))
            };
            return Err(Error::param(format!(
                "scene {scene} has no parameter {k:?}; {list}"
            )));
        }
        Ok(Params { scene, map })
    }

    /// An integer parameter in `[min, max]`, `default` when absent.
    pub(super) fn int(&self, key: &str, default: u64, min: u64, max: u64) -> Result<u64> {
        self.number(key, default, min, max, "a whole number")
    }

    /// A real parameter in `[min, max]`, `default` when absent.
    pub(super) fn real(&self, key: &str, default: f32, min: f32, max: f32) -> Result<f32> {
        self.number(key, default, min, max, "a number")
    }

    /// A parameter parsed as a `T` (`kind` names what it must be) in `[min, max]` (a NaN is
    /// outside), `default` when absent.
    fn number<T>(&self, key: &str, default: T, min: T, max: T, kind: &str) -> Result<T>
    where
        T: std::str::FromStr + PartialOrd + std::fmt::Display,
    {
        let Some(text) = self.map.get(key) else {
            return Ok(default);
        };
        let v: T = text.trim().parse().map_err(|_| {
            Error::param(format!(
                "scene {}: parameter {key}={text:?} is not {kind}",
                self.scene
            ))
        })?;
        if !(v >= min && v <= max) {
            return Err(Error::param(format!(
                "scene {}: parameter {key}={v} is outside [{min}, {max}]",
                self.scene
            )));
        }
        Ok(v)
    }

    /// A yes/no parameter (`true`/`false`, `yes`/`no`, `1`/`0`), `default` when absent.
    pub(super) fn flag(&self, key: &str, default: bool) -> Result<bool> {
        let Some(text) = self.map.get(key) else {
            return Ok(default);
        };
        match text.trim().to_ascii_lowercase().as_str() {
            "true" | "yes" | "1" | "on" => Ok(true),
            "false" | "no" | "0" | "off" => Ok(false),
            _ => Err(Error::param(format!(
                "scene {}: parameter {key}={text:?} is not true or false",
                self.scene
            ))),
        }
    }
}
