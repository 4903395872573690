//! `pcss`: percentage-closer soft shadows (Fernando 2005, "Percentage-closer soft
//! shadows", SIGGRAPH sketch; NVIDIA's `PCSS` sample).
//!
//! One shadow map from the light's centre, then per receiver the paper's three steps: the
//! *blocker search* and *penumbra estimation* of
//! [`blocker_search`](super::filtering::blocker_search) (mean blocker depth over the
//! light's cone from the receiver, penumbra width by similar triangles), then *filtering*:
//! percentage-closer filtering with a kernel of that width, so shadows are hard at
//! contact and soften with distance (contact hardening).
//!
//! Parameters are named as engines name them: `light-size` (NVIDIA's `LIGHT_WORLD_SIZE`;
//! 0 takes the side of the square of equal area to the frame's area light, which is what
//! the reference integrates over), `blocker-samples` (`BLOCKER_SEARCH_NUM_SAMPLES`) and
//! `filter-samples` (`PCF_NUM_SAMPLES`), plus the shadow map's `resolution`, `bias` and
//! `slope-bias`.
//!
//! Departures: the sample's Poisson disks become regular grids of `⌈√samples⌉²` taps
//! spread over the region (deterministic; no random rotation to trade banding for noise);
//! each filter tap is a bilinearly weighted 2×2 comparison as in `pcf`. A point light's
//! cube (the stand-in of a rectangle, disk or sphere light) keeps each receiver's search
//! and filter in its own face: taps beyond the face edge read the edge.
//! Known artifacts: PCSS averages blockers, so overlapping casters at different depths
//! share one penumbra width; thin casters can fall between search taps; the slope bias
//! grows with the kernel, detaching wide penumbrae slightly; the kernel is a square, the
//! light's shape is not modelled.

use super::filtering::blocker_search::{grid_offset, grid_side, BlockerSearch};
use super::shadow_map::{
    bilinear_compare, check_light_map_size, check_resolution, light_view_count, receiver_bias,
    render_light_maps, DEFAULT_CONSTANT_BIAS, DEFAULT_RESOLUTION, DEFAULT_SLOPE_BIAS,
};
use super::{
    find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique, Shadows,
    Stats, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::Result;
use crate::math::Vec3;
use crate::raster::DepthBuffer;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Default blocker-search taps (an 8 × 8 grid): NVIDIA's sample uses 16–64 Poisson taps;
/// fewer miss thin casters, more cost linearly.
pub const DEFAULT_BLOCKER_SAMPLES: u32 = 64;
/// Default filter taps (a 12 × 12 grid of 2×2 comparisons): enough for penumbrae tens of
/// texels wide without visible steps.
pub const DEFAULT_FILTER_SAMPLES: u32 = 144;

const LIGHT_SIZE: ParamSpec = ParamSpec::real(
    "light-size",
    0.0,
    1e9,
    "light width in world units (a distant light: its angular width in radians); 0 = the square of equal area to the frame's area light",
);
const BLOCKER_SAMPLES: ParamSpec = ParamSpec::int(
    "blocker-samples",
    1,
    1024,
    "taps of the blocker search (a square grid): fewer miss thin casters",
);
const FILTER_SAMPLES: ParamSpec = ParamSpec::int(
    "filter-samples",
    1,
    4096,
    "PCF taps over the penumbra (a square grid, each a bilinear 2x2 comparison)",
);

/// Percentage-closer soft shadows.
#[derive(Clone, Debug)]
pub struct Pcss {
    /// Map side in texels.
    pub resolution: u32,
    /// Constant bias in texels.
    pub bias: f32,
    /// Slope-scaled bias in texels per unit of tan θ.
    pub slope_bias: f32,
    /// Light width (0 = from the area light).
    pub light_size: f32,
    /// Blocker-search taps.
    pub blocker_samples: u32,
    /// Filter taps.
    pub filter_samples: u32,
}

impl Default for Pcss {
    fn default() -> Self {
        Pcss {
            resolution: DEFAULT_RESOLUTION,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            light_size: 0.0,
            blocker_samples: DEFAULT_BLOCKER_SAMPLES,
            filter_samples: DEFAULT_FILTER_SAMPLES,
        }
    }
}

/// Percentage-closer filtering on a `side²` grid over a square of `radius` texels about
/// `(fx, fy)`, each tap a bilinearly weighted 2×2 comparison against `depth`.
fn filter(map: &DepthBuffer, fx: f32, fy: f32, radius: f32, side: u32, depth: f32) -> f32 {
    let mut sum = 0.0;
    for j in 0..side {
        for i in 0..side {
            let tx = fx + grid_offset(i, side) * radius - 0.5;
            let ty = fy + grid_offset(j, side) * radius - 0.5;
            let (x0, y0) = (tx.floor(), ty.floor());
            sum += bilinear_compare(map, x0 as i64, y0 as i64, tx - x0, ty - y0, depth);
        }
    }
    sum / (side * side) as f32
}

/// The light width a penumbra estimate uses: `light_size` when positive, else the side
/// of the square of equal area to the frame's area light (0 under a punctual light: hard
/// shadows).
pub fn light_width(light_size: f32, frame: &Frame) -> f32 {
    if light_size > 0.0 {
        return light_size;
    }
    frame.area.map_or(0.0, |a| a.equivalent_width())
}

impl ShadowTechnique for Pcss {
    fn name(&self) -> &'static str {
        "pcss"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
            ("light-size".to_string(), param_value(self.light_size)),
            ("blocker-samples".to_string(), self.blocker_samples.into()),
            ("filter-samples".to_string(), self.filter_samples.into()),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![
            BIAS,
            BLOCKER_SAMPLES,
            FILTER_SAMPLES,
            LIGHT_SIZE,
            RESOLUTION,
            SLOPE_BIAS,
        ]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "pcss";
        let spec = find_param(t, &self.param_specs(), key)?;
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            "light-size" => self.light_size = spec.f32(t, value)?,
            "blocker-samples" => self.blocker_samples = spec.u32(t, value)?,
            "filter-samples" => self.filter_samples = spec.u32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let mut stats = Stats::default();
        let res = check_resolution("pcss", self.resolution)?;
        check_light_map_size("pcss", light_view_count(frame.light), res)?;
        let maps = stats.stage("shadow_map", || render_light_maps(frame, res));
        let faces: Vec<BlockerSearch> = maps
            .views
            .iter()
            .zip(&maps.maps)
            .map(|(view, map)| BlockerSearch::new(view, map))
            .collect();
        let view = frame.view;
        let width = light_width(self.light_size, frame);
        let (search_side, filter_side) = (
            grid_side(self.blocker_samples),
            grid_side(self.filter_samples),
        );
        let (bias, slope_bias) = (self.bias, self.slope_bias);
        let value = stats.stage("lookup", || {
            (0..(view.width * view.height) as usize)
                .into_par_iter()
                .with_min_len(512)
                .map(|k| {
                    if let Some(v) = frame.unreached(k) {
                        return v;
                    }
                    let p = view.position[k];
                    let face = &faces[maps.select(frame.light, p)];
                    let s = face.view.project(p);
                    if !(s.u.is_finite() && s.v.is_finite() && s.depth.is_finite()) {
                        return Vec3::ONE;
                    }
                    let (l, n) = (frame.light.shadow_ray(p).0, view.normal[k]);
                    let texel = face.view.texel_size(res, s.depth);
                    let d = s.depth - receiver_bias(texel, n, l, bias, slope_bias);
                    let Some(radius) = face.penumbra_radius(&s, d, width, search_side) else {
                        return Vec3::ONE;
                    };
                    // The slope term grows with the kernel, as in `pcf`.
                    let d = s.depth - receiver_bias(texel, n, l, bias, slope_bias * (radius + 1.0));
                    let (fx, fy) = (s.u * res as f32, s.v * res as f32);
                    Vec3::splat(filter(face.map, fx, fy, radius, filter_side, d))
                })
                .collect()
        });
        stats.memory_bytes = maps.memory_bytes();
        stats.count("map_texels", (res as f64).powi(2) * maps.maps.len() as f64);
        if frame.dumping() {
            for (i, m) in maps.maps.iter().enumerate() {
                frame.dump_depth(&format!("pcss-map{i}.png"), m)?;
            }
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
