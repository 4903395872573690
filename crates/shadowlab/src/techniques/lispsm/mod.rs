//! `lispsm`: light-space perspective shadow maps (Wimmer, Scherzer & Purgathofer, "Light
//! Space Perspective Shadow Maps", EGSR 2004).
//!
//! The idea: like `psm`, redistribute texels with a perspective transform so that shadows
//! near the viewer get more of them, but take the perspective in *light space* — a frustum
//! `P` whose axis is perpendicular to the light — instead of the camera's post-perspective
//! space. The light stays directional in `P`'s space (no inverted or point-light cases),
//! the warp's strength is a free parameter `n`, and the paper's `n_opt` spreads the
//! aliasing error evenly over the view depth range ([`warp`]).
//!
//! One frame: the receivers the light can reach (from the camera pass) give the body's
//! light-space rectangle and depth; the scene's nearest point towards the light closes the
//! depth range so every caster is inside; `P`'s eye sits `n` before the body's near face at
//! the camera's `x`; the map is the orthographic view along the light of `P`'s
//! post-perspective space, fitted to the body. Depths are linear light depths; the biases
//! are `sm`'s, in texels of the warped map at the receiver (the texel grows along `y` as
//! `y′²`, so the larger of the two texel sides is used).
//!
//! Invariants: every receiver the light reaches maps inside the map; `n → ∞` gives the
//! uniform map of `sm` (fitted to the same receivers). Under an orthographic camera there
//! is no perspective aliasing to undo, and the automatic `n` is that limit (capped at
//! [`warp::MAX_N_RATIO`] body depths): a uniform map. Departures: the body is the box of
//! the visible lit receivers (the paper intersects the view frustum with the scene and
//! the light's extrusion), a tighter fit with the same guarantee since only visible
//! receivers are looked up; `n` is capped at [`warp::MAX_N_RATIO`] body depths. Spot and
//! point lights, which the paper handles by first mapping the light to a directional one
//! through its own perspective, fall back here to `sm`'s map (the counter
//! `single_map_fallback` says so). Known artifacts: as `psm`'s, the gain vanishes when the
//! light is parallel to the view direction (sin γ → 0, a uniform map); the warped texels
//! grow fast beyond the body's far end, which holds no receiver; projection aliasing is
//! not reduced.

pub mod warp;

use super::shadow_map::{
    check_light_map_size, check_resolution, lookup_nearest, lookup_pcf, receiver_bias,
    render_depth_map, ShadowMap, DEFAULT_CONSTANT_BIAS, DEFAULT_RESOLUTION, DEFAULT_SLOPE_BIAS,
    DIRECTIONAL_PAD,
};
use super::{
    find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique, Shadows,
    Stats, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::{Error, Result};
use crate::light::{Light, LightView};
use crate::math::{Mat4, Vec3};
use crate::raster::DepthBuffer;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// The warped map of one frame.
pub struct WarpedMap {
    /// World to light space.
    pub basis: Mat4,
    /// The fitted warp.
    pub warp: warp::Warp,
    /// The light view the map was rasterized from.
    pub view: LightView,
    /// The depth map.
    pub map: DepthBuffer,
}

/// The `lispsm` technique.
#[derive(Clone, Debug)]
pub struct LightSpacePerspective {
    /// Map side in texels.
    pub resolution: u32,
    /// `P`'s near distance; `None` for the paper's `n_opt`.
    pub n: Option<f32>,
    /// Constant bias in texels (as `sm`'s).
    pub bias: f32,
    /// Slope-scaled bias in texels per unit of tan θ (as `sm`'s).
    pub slope_bias: f32,
    /// PCF kernel side (0: unfiltered, as `sm` and `psm`).
    pub kernel: u32,
}

impl Default for LightSpacePerspective {
    fn default() -> Self {
        LightSpacePerspective {
            resolution: DEFAULT_RESOLUTION,
            n: None,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            kernel: 0,
        }
    }
}

/// The parameter table, in key order.
const TABLE: &[ParamSpec] = &[
    BIAS,
    ParamSpec::int(
        "kernel",
        0,
        15,
        "PCF kernel side in texels, 0 for one nearest-texel test",
    ),
    ParamSpec::real(
        "n",
        0.0,
        f32::MAX as f64,
        "distance of the warp's eye before the body (0 excluded), or auto for the paper's n_opt",
    ),
    RESOLUTION,
    SLOPE_BIAS,
];

/// Light-space bounds of the lit receivers: x, y, depth ranges and the nearest view depth.
fn receiver_extent(frame: &Frame, basis: &Mat4) -> Option<([f32; 6], f32)> {
    let view = frame.view;
    let cam = frame.camera;
    let f = cam.forward();
    let empty = (
        [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ],
        f32::INFINITY,
    );
    let (b, zn) = (0..view.position.len())
        .into_par_iter()
        .with_min_len(4096)
        .filter(|&k| frame.receiver_lit(k))
        .map(|k| {
            let p = view.position[k];
            let q = basis.transform_point3(p);
            ([q.x, q.x, q.y, q.y, -q.z, -q.z], (p - cam.eye).dot(f))
        })
        .reduce(
            || empty,
            |a, b| {
                let m = &a.0;
                let n = &b.0;
                (
                    [
                        m[0].min(n[0]),
                        m[1].max(n[1]),
                        m[2].min(n[2]),
                        m[3].max(n[3]),
                        m[4].min(n[4]),
                        m[5].max(n[5]),
                    ],
                    a.1.min(b.1),
                )
            },
        );
    (b.iter().all(|v| v.is_finite()) && zn.is_finite()).then_some((b, zn))
}

impl LightSpacePerspective {
    /// The warped map of a frame lit by a directional light towards `to_light`; `None`
    /// when the light reaches no receiver.
    pub fn build(&self, frame: &Frame, to_light: Vec3, res: u32) -> Option<WarpedMap> {
        let (basis, warp, view) = self.fit(frame, to_light)?;
        let map = render_depth_map(frame.scene, &view, res);
        Some(WarpedMap {
            basis,
            warp,
            view,
            map,
        })
    }

    /// The light basis, the fitted warp and the light view of the warped map of a frame
    /// lit towards `to_light`, before any map is drawn (the GPU twin draws it itself);
    /// `None` when the light reaches no receiver.
    pub fn fit(&self, frame: &Frame, to_light: Vec3) -> Option<(Mat4, warp::Warp, LightView)> {
        let scene = &frame.scene.bounds;
        let origin = scene.center() + to_light.normalize() * scene.diagonal().max(1e-6);
        let (basis, sin_gamma) = warp::light_frame(to_light, frame.camera.forward(), origin);
        let (b, zn) = receiver_extent(frame, &basis)?;
        let pad = |lo: f32, hi: f32| {
            let p = ((hi - lo) * DIRECTIONAL_PAD).max(scene.diagonal() * 1e-6);
            ((lo - p) as f64, (hi + p) as f64)
        };
        let near = scene
            .corners()
            .iter()
            .map(|&p| -basis.transform_point3(p).z)
            .fold(f32::INFINITY, f32::min);
        let ext = warp::Extent {
            x: pad(b[0], b[1]),
            y: pad(b[2], b[3]),
            depth: pad(near.min(b[4]), b[5]),
        };
        let d = ext.y.1 - ext.y.0;
        let n = match self.n {
            Some(n) => (n as f64).min(warp::MAX_N_RATIO * d),
            // An orthographic view has no perspective aliasing to undo: the paper's optimum
            // is then the limit n → ∞, the uniform map.
            None if frame.camera.is_orthographic() => warp::MAX_N_RATIO * d,
            None => warp::n_opt(zn.max(frame.camera.near) as f64, d, sin_gamma),
        };
        let ex = basis.transform_point3(frame.camera.eye).x as f64;
        let corners = [
            (ext.x.0, ext.y.0),
            (ext.x.1, ext.y.0),
            (ext.x.0, ext.y.1),
            (ext.x.1, ext.y.1),
        ];
        let w = warp::Warp::fit(&ext, ex, n, corners.into_iter());
        let view = LightView::new(
            basis,
            w.clip_from_light(),
            false,
            ext.depth.0 as f32,
            ext.depth.1 as f32,
            0.0,
        );
        Some((basis, w, view))
    }

    fn lookup(&self, frame: &Frame, m: &WarpedMap) -> Vec<Vec3> {
        let view = frame.view;
        let res = m.map.width;
        let slope = crate::techniques::shadow_map::pcf_slope_bias(self.slope_bias, self.kernel);
        (0..view.position.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| {
                if let Some(v) = frame.unreached(k) {
                    return v;
                }
                let p = view.position[k];
                let s = m.view.project(p);
                let y = m.basis.transform_point3(p).y as f64;
                let (tx, ty) = m.warp.texel_sizes(y, res);
                let (l, _) = frame.light.shadow_ray(p);
                let d =
                    s.depth - receiver_bias(tx.max(ty) as f32, view.normal[k], l, self.bias, slope);
                if !(s.u.is_finite() && s.v.is_finite() && d.is_finite()) {
                    return Vec3::ONE;
                }
                Vec3::splat(if self.kernel == 0 {
                    lookup_nearest(&m.map, s.u, s.v, d)
                } else {
                    lookup_pcf(&m.map, s.u, s.v, d, self.kernel)
                })
            })
            .collect()
    }

    fn fallback(&self, frame: &Frame) -> Result<Shadows> {
        let mut sm = if self.kernel > 0 {
            ShadowMap::pcf()
        } else {
            ShadowMap::standard()
        };
        sm.resolution = self.resolution;
        sm.bias = self.bias;
        sm.slope_bias = self.slope_bias;
        if self.kernel > 0 {
            sm.kernel = self.kernel;
        }
        let mut s = sm.render(frame)?;
        s.stats.count("single_map_fallback", 1.0);
        Ok(s)
    }
}

impl ShadowTechnique for LightSpacePerspective {
    fn name(&self) -> &'static str {
        "lispsm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            (
                "n".to_string(),
                match self.n {
                    Some(n) => param_value(n),
                    None => "auto".into(),
                },
            ),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
            ("kernel".to_string(), self.kernel.into()),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        TABLE.to_vec()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "lispsm";
        let spec = find_param(t, TABLE, key)?;
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "n" => {
                self.n = if value.trim() == "auto" {
                    None
                } else {
                    let n: f32 = parse_value(t, key, value)?;
                    if !(n.is_finite() && n > 0.0) {
                        return Err(Error::param(format!(
                            "parameter lispsm.n = {value:?} must be auto or a positive distance"
                        )));
                    }
                    Some(n)
                }
            }
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            "kernel" => self.kernel = spec.u32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let res = check_resolution("lispsm", self.resolution)?;
        let Light::Directional { to_light } = *frame.light else {
            return self.fallback(frame);
        };
        check_light_map_size("lispsm", 1, res)?;
        let mut stats = Stats::default();
        let Some(m) = stats.stage("shadow_map", || self.build(frame, to_light, res)) else {
            // No receiver the light reaches: nothing can be shadowed.
            let view = frame.view;
            let value = (0..view.position.len())
                .map(|k| {
                    if view.covered(k) {
                        Vec3::ZERO
                    } else {
                        Vec3::ONE
                    }
                })
                .collect();
            return Ok(Shadows::of_frame(frame, value, stats));
        };
        let value = stats.stage("lookup", || self.lookup(frame, &m));
        stats.memory_bytes = m.map.depth.len() as u64 * 4;
        stats.count("n", m.warp.n);
        stats.count("map_texels", m.map.depth.len() as f64);
        if frame.dumping() {
            frame.dump_depth("lispsm-map0.png", &m.map)?;
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
