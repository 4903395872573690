//! `sm` and `pcf`: the standard shadow map (Williams 1978) and percentage-closer
//! filtering (Reeves et al. 1987), the baselines every paper measures against.
//!
//! The light's view is rasterized by the shared rasterizer into a square map of linear
//! depths (one map for directional and spot lights, a cube of six for point lights). A
//! receiver is in shadow when its own light depth, less a bias, lies behind the map.
//! An alpha-masked caster's texels are left out of the map where its texture cuts it out
//! (the texture read at each texel centre's barycentrics), as in every map built here.
//!
//! PCF here is the software equivalent of hardware PCF: each of the `kernel × kernel`
//! taps makes four depth comparisons at the surrounding texel centres and weighs them
//! bilinearly, so the result varies smoothly as the look-up moves across texels.
//!
//! Bias: the depth offset is `texel · (bias + slope_bias · min(tan θ, 10))`, where `texel`
//! is the world size of one map texel at the receiver and θ the angle between the normal
//! and the light direction. In texel units it is independent of the scene's units. PCF
//! compares at texels up to `kernel/2 + 1` away, so its slope term is scaled by that radius.
//! Known artifacts: acne where the bias is too small for the slope, peter-panning where it
//! is too large, and the blocky edges of magnified texels.

use super::{
    find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique, Shadows,
    Stats, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::{Error, Result};
use crate::light::{cube_face, light_views, Light, LightView};
use crate::limits;
use crate::math::Vec3;
use crate::raster::{self, DepthBuffer, MAX_RASTER_SIDE};
use crate::scene::Scene;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Default map side in texels.
pub const DEFAULT_RESOLUTION: u32 = 2048;
/// Default constant bias in texels: covers the depth error of rasterizing the map and of
/// looking up a texel centre up to half a texel from the receiver on a surface facing the
/// light. Larger values detach shadows from their casters (peter-panning).
pub const DEFAULT_CONSTANT_BIAS: f32 = 0.5;
/// Default slope-scaled bias in texels per unit of tan θ: a surface at angle θ changes
/// depth by tan θ per texel, and a look-up lands up to √2/2 texel from the texel centre
/// that was rasterized. Smaller values give acne on slopes.
pub const DEFAULT_SLOPE_BIAS: f32 = 1.0;
/// Default PCF kernel side in texels.
pub const DEFAULT_PCF_KERNEL: u32 = 3;
/// The PCF kernel parameter.
pub const PCF_KERNEL: ParamSpec = ParamSpec::int(
    "kernel",
    1,
    15,
    "PCF kernel side in texels: wider blurs the shadow edge over more texels",
);
/// The slope factor is clamped here so grazing surfaces do not push shadows off entirely.
const MAX_SLOPE: f32 = 10.0;
/// Fraction of the fitted directional view added on each side so filters near the edge
/// of the visible receivers still read valid texels.
pub const DIRECTIONAL_PAD: f32 = 0.01;

/// The light-space depth maps of one light: one per view.
#[derive(Clone, Debug)]
pub struct LightMaps {
    /// The views (one, or six cube faces for a point light).
    pub views: Vec<LightView>,
    /// The depth map of each view.
    pub maps: Vec<DepthBuffer>,
    /// Map side in texels.
    pub resolution: u32,
}

impl LightMaps {
    /// Bytes held by the maps.
    pub fn memory_bytes(&self) -> u64 {
        // Depth only: the ids are kept for debugging and other techniques, not needed by sm.
        self.maps.iter().map(|m| m.depth.len() as u64 * 4).sum()
    }

    /// The view and map index that `p` falls in.
    #[inline]
    pub fn select(&self, light: &Light, p: Vec3) -> usize {
        match *light {
            Light::Point { position } => cube_face(p - position),
            _ => 0,
        }
    }
}

/// The slope-scaled bias a look-up with PCF `kernel` (0 for none) applies: `slope_bias`,
/// scaled by the kernel's reach (`kernel / 2 + 1` texels), since PCF compares the receiver
/// with texels that far away.
pub fn pcf_slope_bias(slope_bias: f32, kernel: u32) -> f32 {
    if kernel > 0 {
        slope_bias * (kernel / 2 + 1) as f32
    } else {
        slope_bias
    }
}

/// Checks a shadow-map resolution before anything is allocated.
pub fn check_resolution(technique: &str, res: u32) -> Result<u32> {
    if res == 0 || res > MAX_RASTER_SIDE {
        return Err(Error::Limit(format!(
            "{technique}.resolution = {res} is outside 1..={MAX_RASTER_SIDE}; set a smaller --param resolution"
        )));
    }
    Ok(res)
}

/// Bytes the light-space maps of one render may take together, at most: one 16384² map
/// or a cube of six 8192² faces, while a 32768² map or a cube of 16384² faces would
/// exhaust the memory of most machines. Below this, [`limits::memory_limit`] decides.
pub const MAX_LIGHT_MAP_BYTES: u64 = 4 << 30;

/// Bytes a light-map texel takes while the map is rasterized: a depth and a triangle id
/// (8) in the rasterizer's tiles and again in the assembled map.
pub const LIGHT_MAP_BYTES_PER_TEXEL: u64 = 16;

/// Refuses `views` light maps of `res²` texels whose depth and id buffers would exceed
/// [`MAX_LIGHT_MAP_BYTES`] or the memory this process may use ([`limits::check_bytes`]),
/// naming the technique's resolution, the estimate and the limit, before anything is
/// allocated.
pub fn check_light_map_size(technique: &str, views: usize, res: u32) -> Result<()> {
    let texels = views as u64 * (res as u64).pow(2);
    if texels * 8 > MAX_LIGHT_MAP_BYTES {
        return Err(Error::Limit(format!(
            "{technique}.resolution = {res}: {views} light map(s) of {res}² texels would take {} MiB, more than the limit of {} MiB; set a smaller --param resolution",
            (texels * 8) >> 20,
            MAX_LIGHT_MAP_BYTES >> 20
        )));
    }
    limits::check_bytes(
        || format!("{technique}.resolution = {res}: {views} light map(s) of {res}² texels"),
        texels * LIGHT_MAP_BYTES_PER_TEXEL,
    )
}

/// Number of light views [`render_light_maps`] renders for `light`: six for a point light's
/// cube, one otherwise.
pub fn light_view_count(light: &Light) -> usize {
    match light {
        Light::Point { .. } => 6,
        _ => 1,
    }
}

/// Rasterizes `scene` into a `res × res` linear-depth map of `view`.
pub fn render_depth_map(scene: &Scene, view: &LightView, res: u32) -> DepthBuffer {
    let m = view.clip_from_world;
    let lv = view.light_from_world;
    let setups = raster::setup(scene.len(), res, res, |i| {
        let t = scene.triangle(i);
        (
            t.map(|p| m * p.extend(1.0)),
            t.map(|p| -lv.transform_point3(p).z),
        )
    });
    let masked = scene.has_alpha_masks();
    raster::depth_buffer_where(&setups, res, res, |f| {
        !masked || !scene.cut_out(f.id as usize, f.bary())
    })
}

/// The views and maps of `light` for this frame, fitted to the visible receivers.
pub fn render_light_maps(frame: &Frame, res: u32) -> LightMaps {
    let receivers = frame.view.receiver_bounds();
    let views = light_views(
        frame.light,
        &receivers,
        &frame.scene.bounds,
        DIRECTIONAL_PAD,
    );
    let maps = views
        .iter()
        .map(|v| render_depth_map(frame.scene, v, res))
        .collect();
    LightMaps {
        views,
        maps,
        resolution: res,
    }
}

/// A standard shadow map, optionally with percentage-closer filtering.
#[derive(Clone, Debug)]
pub struct ShadowMap {
    name: &'static str,
    /// Map side in texels.
    pub resolution: u32,
    /// Constant bias in texels.
    pub bias: f32,
    /// Slope-scaled bias in texels per unit of tan θ.
    pub slope_bias: f32,
    /// PCF kernel side (0 for the unfiltered standard map).
    pub kernel: u32,
}

impl ShadowMap {
    /// The standard shadow map `sm`.
    pub fn standard() -> Self {
        ShadowMap {
            name: "sm",
            resolution: DEFAULT_RESOLUTION,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            kernel: 0,
        }
    }

    /// Percentage-closer filtering `pcf`.
    pub fn pcf() -> Self {
        ShadowMap {
            name: "pcf",
            kernel: DEFAULT_PCF_KERNEL,
            ..Self::standard()
        }
    }
}

/// The smallest cos θ the slope term divides by: a receiver edge-on to the light would make
/// tan θ infinite; its slope factor is [`MAX_SLOPE`] either way, long before this.
const MIN_COSINE: f32 = 1e-6;

/// The depth offset of a receiver, in world units (see the module doc).
#[inline]
pub fn receiver_bias(texel: f32, n: Vec3, l: Vec3, bias: f32, slope_bias: f32) -> f32 {
    let cos = n.dot(l).clamp(MIN_COSINE, 1.0);
    let tan = ((1.0 - cos * cos).max(0.0).sqrt() / cos).min(MAX_SLOPE);
    texel * (bias + slope_bias * tan)
}

/// Unfiltered look-up: 1 when `depth` is not behind the texel that `(u, v)` falls in.
#[inline]
pub fn lookup_nearest(map: &DepthBuffer, u: f32, v: f32, depth: f32) -> f32 {
    let n = map.width;
    let x = ((u * n as f32).floor() as i64).clamp(0, n as i64 - 1) as u32;
    let y = ((v * n as f32).floor() as i64).clamp(0, n as i64 - 1) as u32;
    if depth > map.depth[(y * n + x) as usize] {
        0.0
    } else {
        1.0
    }
}

/// One bilinearly weighted 2×2 comparison of `depth` with the texels `(x, y)` to
/// `(x + 1, y + 1)` (clamped to the map), weights `ax`, `ay` towards the second ones.
#[inline]
pub fn bilinear_compare(map: &DepthBuffer, x: i64, y: i64, ax: f32, ay: f32, depth: f32) -> f32 {
    let n = map.width as i64;
    let test = |x: i64, y: i64| -> f32 {
        let x = x.clamp(0, n - 1);
        let y = y.clamp(0, n - 1);
        if depth > map.depth[(y * n + x) as usize] {
            0.0
        } else {
            1.0
        }
    };
    let top = test(x, y) * (1.0 - ax) + test(x + 1, y) * ax;
    let bottom = test(x, y + 1) * (1.0 - ax) + test(x + 1, y + 1) * ax;
    top * (1.0 - ay) + bottom * ay
}

/// PCF look-up: `kernel × kernel` bilinearly weighted 2×2 comparisons around `(u, v)`.
#[inline]
pub fn lookup_pcf(map: &DepthBuffer, u: f32, v: f32, depth: f32, kernel: u32) -> f32 {
    let n = map.width as i64;
    let fx = u * n as f32 - 0.5;
    let fy = v * n as f32 - 0.5;
    let x0 = fx.floor();
    let y0 = fy.floor();
    let ax = fx - x0;
    let ay = fy - y0;
    let r = (kernel as i64 - 1) / 2;
    let k = kernel as i64;
    let mut sum = 0.0;
    for dy in -r..k - r {
        for dx in -r..k - r {
            sum += bilinear_compare(map, x0 as i64 + dx, y0 as i64 + dy, ax, ay, depth);
        }
    }
    sum / (kernel * kernel) as f32
}

impl ShadowTechnique for ShadowMap {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
        ]);
        if self.kernel > 0 {
            m.insert("kernel".into(), self.kernel.into());
        }
        m
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        let mut table = vec![BIAS, RESOLUTION, SLOPE_BIAS];
        if self.kernel > 0 {
            table.insert(1, PCF_KERNEL);
        }
        table
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = self.name;
        let spec = find_param(t, &self.param_specs(), key)?;
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            "kernel" => self.kernel = spec.u32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let mut stats = Stats::default();
        let res = check_resolution(self.name, self.resolution)?;
        check_light_map_size(self.name, light_view_count(frame.light), res)?;
        let maps = stats.stage("shadow_map", || render_light_maps(frame, res));
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let kernel = self.kernel;
        let slope = pcf_slope_bias(self.slope_bias, kernel);
        let bias = self.bias;
        let value = stats.stage("lookup", || {
            (0..(w * h) as usize)
                .into_par_iter()
                .with_min_len(1024)
                .map(|k| {
                    if let Some(v) = frame.unreached(k) {
                        return v;
                    }
                    let p = view.position[k];
                    let i = maps.select(frame.light, p);
                    let lv = &maps.views[i];
                    let s = lv.project(p);
                    let (l, _) = frame.light.shadow_ray(p);
                    let d = s.depth
                        - receiver_bias(
                            lv.texel_size(res, s.depth),
                            view.normal[k],
                            l,
                            bias,
                            slope,
                        );
                    if !(s.u.is_finite() && s.v.is_finite() && d.is_finite()) {
                        // A receiver whose light-space position overflows f32 (found by
                        // fuzzing extreme coordinates) has no texel to compare with.
                        return Vec3::ONE;
                    }
                    let lit = if kernel == 0 {
                        lookup_nearest(&maps.maps[i], s.u, s.v, d)
                    } else {
                        lookup_pcf(&maps.maps[i], s.u, s.v, d, kernel)
                    };
                    Vec3::splat(lit)
                })
                .collect()
        });
        stats.memory_bytes = maps.memory_bytes();
        stats.count("map_texels", (res as f64).powi(2) * maps.maps.len() as f64);
        if frame.dumping() {
            for (i, m) in maps.maps.iter().enumerate() {
                frame.dump_depth(&format!("{}-map{i}.png", self.name), m)?;
            }
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
