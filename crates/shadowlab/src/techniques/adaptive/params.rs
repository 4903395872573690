//! The parameters of adaptive shadow maps (Fernando et al. 2001): the tree's shape (the
//! starting resolution of Section 5, the tiles and cells of Section 3), the memory limit of
//! Section 3.2, the analysed share of Section 4.3, the time limit and cost terms of
//! Section 3.1, and the bias of Section 4.2's depth comparison.

use crate::error::{Error, Result};
use crate::raster;
use crate::techniques::shadow_map::{DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS};
use crate::techniques::technique::{
    check_range, find_param, param_value, parse_value, ParamRange, ParamSpec, BIAS, SLOPE_BIAS,
};
use std::collections::BTreeMap;

/// Default side of a root node's tile in texels (the paper's starting resolution).
pub const DEFAULT_ROOT_RESOLUTION: u32 = 512;
/// Default side of every other node's tile in texels.
pub const DEFAULT_TILE_RESOLUTION: u32 = 32;
/// Default number of cells per side of a node: each level refines texels by this factor.
pub const DEFAULT_CELLS: u32 = 4;
/// Default memory budget in MiB (the paper's 16 MB, the size of a 2048² map of 32-bit depths).
pub const DEFAULT_BUDGET_MB: f64 = 16.0;
/// Default share of eye pixels analysed per frame (the paper's one eighth).
pub const DEFAULT_ANALYSIS_FRACTION: f64 = 0.125;
/// Default per-frame budget for new nodes, in the cost model's (nominal) milliseconds.
pub const DEFAULT_TIME_BUDGET_MS: f64 = 40.0;
/// Default cost of a new tile per texel in the cost model (`a`), in nominal nanoseconds:
/// a fixed unit, not a measurement, so that the refinement budget (`time-budget-ms`) buys
/// the same nodes on any machine and under any load and a frame's result depends on its
/// inputs alone. The value is about what a 32² tile costs per texel on a 2-core machine;
/// `cost-per-texel-ns=auto` measures this machine instead (and gives up determinism).
pub const DEFAULT_COST_PER_TEXEL_NS: f64 = 50.0;
/// Default fixed cost of a new tile in the cost model (`b`), in nominal milliseconds (see
/// [`DEFAULT_COST_PER_TEXEL_NS`]); `cost-per-tile-ms=auto` measures it.
pub const DEFAULT_COST_PER_TILE_MS: f64 = 0.2;
/// Default cap on new nodes per frame.
pub const DEFAULT_MAX_NEW_NODES: u32 = 1024;
/// Default number of refinement passes per frame (the paper makes one): each further pass
/// examines again the pixels whose cells were just refined, in the new nodes, so a view
/// reaches its resolution in fewer frames.
pub const DEFAULT_PASSES: u32 = 4;
/// Default linear ratio of shadow-map to eye resolution that refinement aims for. Larger
/// values put shadow edges closer to where a ray-traced reference puts them and spend more
/// memory and time; 1 is the paper's criterion.
pub const DEFAULT_OVERSAMPLING: f32 = 16.0;
/// Bytes per MiB, the unit of `budget-mb`.
pub(super) const MIB: f64 = 1024.0 * 1024.0;

/// The technique's parameters.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Params {
    pub(super) root_resolution: u32,
    pub(super) tile_resolution: u32,
    pub(super) cells: u32,
    pub(super) budget_mb: f64,
    pub(super) analysis_fraction: f64,
    pub(super) time_budget_ms: Option<f64>,
    pub(super) max_new_nodes: u32,
    pub(super) passes: u32,
    pub(super) oversampling: f32,
    pub(super) bias: f32,
    pub(super) slope_bias: f32,
    pub(super) cost_per_texel_ns: Option<f64>,
    pub(super) cost_per_tile_ms: Option<f64>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            root_resolution: DEFAULT_ROOT_RESOLUTION,
            tile_resolution: DEFAULT_TILE_RESOLUTION,
            cells: DEFAULT_CELLS,
            budget_mb: DEFAULT_BUDGET_MB,
            analysis_fraction: DEFAULT_ANALYSIS_FRACTION,
            time_budget_ms: Some(DEFAULT_TIME_BUDGET_MS),
            max_new_nodes: DEFAULT_MAX_NEW_NODES,
            passes: DEFAULT_PASSES,
            oversampling: DEFAULT_OVERSAMPLING,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            cost_per_texel_ns: Some(DEFAULT_COST_PER_TEXEL_NS),
            cost_per_tile_ms: Some(DEFAULT_COST_PER_TILE_MS),
        }
    }
}

/// The technique's name in parameter errors.
const T: &str = "asm";

/// The parameter table, in the order `ShadowTechnique::params` lists the keys.
const TABLE: &[ParamSpec] = &[
    ParamSpec::real(
        "analysis-fraction",
        0.0,
        1.0,
        "share of the pixels analysed per frame (0 excluded), rounded to 1/n: the paper's 1/8",
    ),
    BIAS,
    ParamSpec::real(
        "budget-mb",
        0.01,
        1.0e6,
        "MiB the tree of tiles may hold (the paper's memory limit)",
    ),
    ParamSpec::int(
        "cells",
        2,
        64,
        "cells per node side, a power of two dividing tile-resolution: the refinement per level",
    ),
    ParamSpec::real(
        "cost-per-texel-ns",
        0.0,
        1.0e9,
        "the cost model's a in nominal ns per texel, or auto to measure it at start-up",
    ),
    ParamSpec::real(
        "cost-per-tile-ms",
        0.0,
        1.0e7,
        "the cost model's b in nominal ms per tile, or auto to measure it at start-up",
    ),
    ParamSpec::int("max-new-nodes", 0, 1_000_000, "new nodes per frame at most"),
    ParamSpec::real(
        "oversampling",
        0.01,
        1024.0,
        "texels wanted across an eye pixel's footprint, per axis (1 is the paper's criterion)",
    ),
    ParamSpec::int(
        "passes",
        1,
        64,
        "refinement passes per frame (1 is the paper's)",
    ),
    ParamSpec::int(
        "root-resolution",
        16,
        raster::MAX_RASTER_SIDE as i64,
        "side of a root tile in texels, a power of two; a point light's cube faces get half",
    ),
    SLOPE_BIAS,
    ParamSpec::int(
        "tile-resolution",
        8,
        2048,
        "side of every non-root node's tile in texels, a power of two",
    ),
    ParamSpec::real(
        "time-budget-ms",
        0.0,
        1.0e7,
        "predicted ms of new tiles per frame in the cost model's units, or none for no limit",
    ),
];

impl Params {
    /// Side of a root tile for a light with `views` views.
    pub(super) fn face_resolution(&self, views: usize) -> u32 {
        if views > 1 {
            (self.root_resolution / 2).max(1)
        } else {
            self.root_resolution
        }
    }

    /// The memory budget in bytes.
    pub(super) fn budget_bytes(&self) -> u64 {
        (self.budget_mb * MIB) as u64
    }

    /// Checks the parameters that constrain one another.
    pub(super) fn check_structure(&self, views: usize) -> Result<()> {
        let face = self.face_resolution(views);
        let cell = self.tile_resolution / self.cells;
        if cell == 0 || cell * self.cells != self.tile_resolution {
            return Err(Error::param(format!(
                "asm.cells = {} must divide asm.tile-resolution = {}",
                self.cells, self.tile_resolution
            )));
        }
        if face < cell || face / cell * cell != face {
            return Err(Error::param(format!(
                "asm.root-resolution = {} gives root tiles of {face} texels, which the cells of {cell} texels \
                 (asm.tile-resolution / asm.cells) must divide",
                self.root_resolution
            )));
        }
        Ok(())
    }

    /// True when `other` differs in a parameter the tree's shape depends on.
    pub(super) fn reshapes(&self, other: &Params) -> bool {
        other.root_resolution != self.root_resolution
            || other.tile_resolution != self.tile_resolution
            || other.cells != self.cells
    }

    /// The parameters by key, as `ShadowTechnique::params` lists them.
    pub(super) fn to_map(&self) -> BTreeMap<String, serde_json::Value> {
        let p = self;
        let opt = |v: Option<f64>, word: &str| {
            v.map_or(serde_json::Value::from(word), serde_json::Value::from)
        };
        BTreeMap::from([
            ("root-resolution".to_string(), p.root_resolution.into()),
            ("tile-resolution".to_string(), p.tile_resolution.into()),
            ("cells".to_string(), p.cells.into()),
            ("budget-mb".to_string(), p.budget_mb.into()),
            ("analysis-fraction".to_string(), p.analysis_fraction.into()),
            ("time-budget-ms".to_string(), opt(p.time_budget_ms, "none")),
            ("max-new-nodes".to_string(), p.max_new_nodes.into()),
            ("passes".to_string(), p.passes.into()),
            ("oversampling".to_string(), param_value(p.oversampling)),
            ("bias".to_string(), param_value(p.bias)),
            ("slope-bias".to_string(), param_value(p.slope_bias)),
            (
                "cost-per-texel-ns".to_string(),
                opt(p.cost_per_texel_ns, "auto"),
            ),
            (
                "cost-per-tile-ms".to_string(),
                opt(p.cost_per_tile_ms, "auto"),
            ),
        ])
    }

    /// The parameter table.
    pub(super) fn specs() -> Vec<ParamSpec> {
        TABLE.to_vec()
    }

    /// Sets `key` to `value`, checked against the table; on an error `self` is unchanged.
    pub(super) fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let spec = find_param(T, TABLE, key)?;
        let p = self;
        match key {
            "root-resolution" => p.root_resolution = power_of_two(&spec, value)?,
            "tile-resolution" => p.tile_resolution = power_of_two(&spec, value)?,
            "cells" => p.cells = power_of_two(&spec, value)?,
            "budget-mb" => p.budget_mb = real(&spec, value)?,
            "analysis-fraction" => {
                let f: f64 = parse_value(T, key, value)?;
                if !(f > 0.0 && f <= 1.0) {
                    return Err(Error::param(format!(
                        "parameter asm.{key} = {value} is outside its range (0, 1]"
                    )));
                }
                p.analysis_fraction = f;
            }
            "time-budget-ms" => p.time_budget_ms = optional(&spec, value, "none")?,
            "max-new-nodes" => p.max_new_nodes = spec.u32(T, value)?,
            "passes" => p.passes = spec.u32(T, value)?,
            "oversampling" => p.oversampling = spec.f32(T, value)?,
            "bias" => p.bias = spec.f32(T, value)?,
            "slope-bias" => p.slope_bias = spec.f32(T, value)?,
            "cost-per-texel-ns" => p.cost_per_texel_ns = optional(&spec, value, "auto")?,
            "cost-per-tile-ms" => p.cost_per_tile_ms = optional(&spec, value, "auto")?,
            _ => {
                return Err(Error::Internal(format!(
                    "asm.{key} is in the table but not read"
                )))
            }
        }
        Ok(())
    }
}

/// Parses a real parameter as `f64` (the table's reader parses `f32`, which would round
/// the value), checking its range.
fn real(spec: &ParamSpec, value: &str) -> Result<f64> {
    let v: f64 = parse_value(T, spec.key, value)?;
    match spec.range {
        ParamRange::Real(lo, hi) => check_range(T, spec.key, v, lo, hi),
        _ => Err(Error::Internal(format!(
            "parameter asm.{} is read as a real number but its table says {}",
            spec.key, spec.range
        ))),
    }
}

/// Parses `word` (`none`, or `auto` for cost terms) as `None`, else a real parameter.
fn optional(spec: &ParamSpec, value: &str, word: &str) -> Result<Option<f64>> {
    if value.trim().eq_ignore_ascii_case(word) {
        return Ok(None);
    }
    real(spec, value).map(Some)
}

/// Parses an integer parameter that must be a power of two.
fn power_of_two(spec: &ParamSpec, value: &str) -> Result<u32> {
    let v = spec.u32(T, value)?;
    if !v.is_power_of_two() {
        return Err(Error::param(format!(
            "parameter asm.{} = {v} must be a power of two",
            spec.key
        )));
    }
    Ok(v)
}
