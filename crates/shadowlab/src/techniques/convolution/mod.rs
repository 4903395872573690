//! `csm`: convolution shadow maps (Annen, Mertens, Bekaert, Seidel & Kautz, "Convolution
//! Shadow Maps", EGSR 2007).
//!
//! The binary shadow test `f(d, z) = H(z − d)` is expanded in a truncated Fourier series
//! whose terms separate into functions of the receiver depth `d` and of the map depth `z`
//! (Eq. 13), so the map can be turned into basis images `sin(c_k z)`, `cos(c_k z)` that are
//! filtered *before* the test: blurred, mip-mapped and read with tri-linear or anisotropic
//! filtering, which removes the screen-space aliasing of minified shadows.
//!
//! Pipeline per frame ([`Convolution::render`], on the chain of [`super::filtering`]): the
//! light's linear depth map (the shared rasterizer, through `shadow_map::render_light_maps`;
//! six cube faces for a point light, each with its own basis images) → `2M` basis values
//! per texel ([`basis`]: Section 4.1's basis images, 8-bit unsigned normalized by default,
//! as in the paper, or f32) → optional separable Gaussian blur → full mip chain → per pixel
//! a filtered look-up whose footprint comes from the camera pass's screen-space derivatives
//! → reconstruction with Eq. 13 ([`reconstruction`]), offset and scaled ([`offset`],
//! Section 3.2.2), clamped to `[0, 1]`. The series itself, its frequencies and its ringing
//! attenuation are in [`expansion`] (Sections 3.1 and 3.2.1).
//!
//! Invariants: `c_k = π(2k − 1)` for `k = 1..=M`; the basis values of texel `p` are
//! `B_{2k−1} = sin(c_k z(p))`, `B_{2k} = cos(c_k z(p))` and the shadow term is
//! `clamp(p + scale · (f − p), 0, 1)` with `f = ½ + Σ_k σ_k (2/c_k)[cos(c_k d′) B_{2k−1} −
//! sin(c_k d′) B_{2k}]`, `σ_k = exp(−α (k/M)²)` (Section 3.2.1), `d′ = d − offset` and `p`
//! the pivot of the scale (Section 3.2.2).
//! Filtering the basis equals filtering the shadow test when `d` is constant over the
//! filter's support (Eq. 8), up to the 8-bit quantization.
//!
//! Departures from the paper, and why:
//! - Eq. 11 prints `sin(c_k(d − z))`, which is 1 where the receiver is *behind* the map;
//!   Eq. 13 (implemented) is `sin(c_k(z − d))`, the shadow test the paper defines in Eq. 1.
//! - The paper offsets or scales (by 2, about 0: `2f`); here both, and the scale is taken
//!   about a pivot `p` ([`DEFAULT_PIVOT`] = 0.1; `pivot = 0` is the paper's scaling): the
//!   paper's `2f` leaves the Gibbs ringing of the shadowed side doubled, the pivot clamps
//!   it away. Scale 2 about 0.1 brings contact shadows two to three times closer to their
//!   casters than the offset alone, for sharper filtered penumbrae; [`DEFAULT_SCALE`]
//!   gives the measurements.
//! - The paper does not give its offset; here the default (`offset = auto`) is the
//!   smallest `t > 0` where the attenuated reconstruction of the step, scaled about the
//!   pivot, first reaches `1 +` [`LIT_MARGIN`] (or comes within
//!   [`OFFSET_PLATEAU_TOLERANCE`] of its plateau where it never does), so a surface that
//!   is its own occluder (`z = d`) is lit, whatever `M`, `α` and scale.
//! - Depths are normalized over the interval from the nearest map texel under the filter
//!   support of a visible receiver that something may shadow to the farthest such receiver
//!   ([`super::filtering::DepthRange::fitted`]; the paper asks for a tightly fitted light
//!   frustum; clamping outside it keeps every receiver's test, and receivers that nothing can
//!   shadow stay lit), into `[0, 1 − 2·offset]` rather than `[0, 1]`:
//!   the series is periodic with period 2 and the offset shifts `z − d` up, so without
//!   that margin a receiver far in front of its neighbours' depths (`z − d + offset` near
//!   or past 1) would fall on the next period's step and turn dark.
//! - The paper's α is not given; [`DEFAULT_ALPHA`] states the trade-off chosen, and
//!   [`DEFAULT_M`] why the default order is the paper's figures' 16 rather than its
//!   recommended 4.
//! - 8-bit maps of at least [`TABLE_MIN_TEXELS`] texels are encoded through a
//!   [`BasisTable`]: the normalized depth is rounded to one of 2¹⁶ levels (as a 16-bit
//!   depth buffer would hold it) and the level's precomputed codes are copied, about a fifth
//!   of the work of evaluating the basis per texel. The rounding moves a code by one, at
//!   most, for 0.3% of the codes at M = 4 and 1.2% at M = 16; 32-bit maps and smaller maps
//!   are encoded directly.
//!
//! Known artifacts (as in the paper): light leaks where an occluder is within about the
//! offset plus the step's half-width of its receiver (0.018 of the depth range at the
//! defaults, ≈ 0.07 at M = 4 unscaled) — contact shadows fade, more so for small M; ringing leaves shadowed areas slightly
//! uneven; a sloped receiver filtered over a wide footprint shades itself once the depth
//! change across the footprint exceeds the offset; point-light cube faces filter up to their
//! own edges only, so wide filters show seams.

pub mod basis;
pub mod expansion;
pub mod offset;
pub mod reconstruction;

pub use basis::{BasisTable, TABLE_LEVELS, TABLE_MIN_TEXELS};
pub use expansion::{sin_cos_pi, Expansion, DEFAULT_ALPHA, DEFAULT_M, MAX_M};
pub use offset::{DEFAULT_PIVOT, DEFAULT_SCALE, LIT_MARGIN, MAX_OFFSET, OFFSET_PLATEAU_TOLERANCE};
pub use reconstruction::Reconstruction;

use super::filtering::{Channel, DepthRange, FilterSettings, FilteredMaps, MapLayout};
use super::shadow_map::{check_resolution, DEFAULT_RESOLUTION};
use super::{
    find_param, in_key_order, not_read, param_value, parse_value, Frame, ParamSpec,
    ShadowTechnique, Shadows, Stats, RESOLUTION,
};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::raster::DepthBuffer;
use basis::encode_row_any_m;
use std::collections::BTreeMap;

/// Storage of the basis images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// 8-bit unsigned normalized, `[-1, 1] → 0..=255` (the paper's setting).
    U8,
    /// 32-bit float.
    F32,
}

/// The `csm` technique.
#[derive(Clone, Debug)]
pub struct Convolution {
    /// Map side in texels.
    pub resolution: u32,
    /// Truncation order M.
    pub m: u32,
    /// Ringing attenuation α.
    pub alpha: f32,
    /// Offset subtracted from the receiver depth, in normalized depth; `None` = automatic.
    pub offset: Option<f32>,
    /// Scale of the reconstructed step before clamping.
    pub scale: f32,
    /// The value the scale is taken about.
    pub pivot: f32,
    /// Storage of the basis images.
    pub precision: Precision,
    /// Blur, mip-mapping and look-up filter.
    pub filtering: FilterSettings,
}

impl Default for Convolution {
    fn default() -> Self {
        Convolution {
            resolution: DEFAULT_RESOLUTION,
            m: DEFAULT_M,
            alpha: DEFAULT_ALPHA,
            offset: None,
            scale: DEFAULT_SCALE,
            pivot: DEFAULT_PIVOT,
            precision: Precision::U8,
            filtering: FilterSettings::default(),
        }
    }
}

/// The parameters of csm's own, beside the filtering ones.
const OWN: &[ParamSpec] = &[
    ParamSpec::real(
        "alpha",
        0.0,
        100.0,
        "ringing attenuation α of the Fourier coefficients: less overshoot, a flatter step",
    ),
    ParamSpec::int(
        "m",
        1,
        MAX_M as i64,
        "Fourier terms of the expansion: 2M basis images (Section 3.2's M)",
    ),
    ParamSpec::real(
        "offset",
        0.0,
        MAX_OFFSET as f64,
        "normalized depth subtracted from the receiver's, or auto for what M, α, scale and pivot need",
    ),
    ParamSpec::real(
        "pivot",
        0.0,
        1.0,
        "the shadow value the scale is taken about: 0 scales the step as the paper does",
    ),
    ParamSpec::choice(
        "precision",
        &["u8", "f32"],
        "storage of the basis images: 8-bit (the paper's) or 32-bit float",
    ),
    RESOLUTION,
    ParamSpec::real(
        "scale",
        0.01,
        100.0,
        "scale of the reconstructed step before clamping: larger is steeper and sharper",
    ),
];

impl Convolution {
    /// The expansion in effect.
    pub fn expansion(&self) -> Expansion {
        Expansion {
            m: self.m,
            alpha: self.alpha,
        }
    }

    /// The offset in effect, in normalized depth.
    pub fn resolved_offset(&self) -> f32 {
        self.offset
            .unwrap_or_else(|| self.expansion().auto_offset_scaled(self.scale, self.pivot))
    }

    /// The frame flow: basis images of the light's depth maps, pre-filtered and looked up
    /// (the chain of [`super::filtering`]), reconstructed per pixel with the offset and
    /// scale in effect.
    fn run<T: Channel>(&self, frame: &Frame, stats: &mut Stats) -> Result<Vec<Vec3>> {
        let exp = self.expansion();
        let offset = self.resolved_offset();
        let layout = MapLayout {
            technique: "csm",
            resolution: self.resolution,
            channels: exp.channels(),
            span: 1.0 - 2.0 * offset,
        };
        let texels = self.resolution as usize * self.resolution as usize;
        // 8-bit maps much larger than the table are encoded through it.
        let tabled = T::BYTES == 1 && texels >= TABLE_MIN_TEXELS;
        let encoder = |r: &DepthRange| {
            let r = *r;
            let table = tabled.then(|| BasisTable::<T>::new(exp.m, r.span));
            move |m: &DepthBuffer, y: u32, row: &mut [T]| {
                let w = m.width as usize;
                let depths = &m.depth[y as usize * w..(y as usize + 1) * w];
                match &table {
                    Some(t) => t.encode_row(&r, depths, row),
                    None => encode_row_any_m(exp.m, &r, depths, row),
                }
            }
        };
        let (scale, pivot) = (self.scale, self.pivot);
        let rec = exp.reconstruction();
        // The decoding is linear: decode(raw) = raw · (decode(1) − decode(0)) + decode(0).
        let (bias, unit) = (T::decode_signed(0.0), T::decode_signed(1.0));
        let test = |d: f32, raw: &[f32]| {
            let f = rec.eval_encoded(d - offset, raw, unit - bias, bias);
            (pivot + scale * (f - pivot)).clamp(0.0, 1.0)
        };
        let (maps, value) =
            FilteredMaps::<T>::shade(frame, &layout, &self.filtering, stats, encoder, test)?;
        self.report(&maps, &layout, offset, stats);
        // sin(c_1 z): blue where positive, red where negative, as in the paper's Figure 5.
        maps.dump_level0(
            frame,
            |i| format!("csm-basis{i}-sin1.png"),
            |t| {
                let b = T::decode_signed(t[0].to_f32());
                let g = (b.abs() * 255.0) as u8;
                if b >= 0.0 {
                    [0, 0, g]
                } else {
                    [g, 0, 0]
                }
            },
        )?;
        Ok(value)
    }

    /// The counters of a frame: basis images, offset, depth range, mip levels.
    fn report<T: Channel>(
        &self,
        maps: &FilteredMaps<T>,
        layout: &MapLayout,
        offset: f32,
        stats: &mut Stats,
    ) {
        stats.count("basis_images", (layout.channels * maps.chains.len()) as f64);
        stats.count("offset", offset as f64);
        if let Some(r) = maps.ranges.first() {
            // The offset in world units: how far in front of a receiver an occluder must be
            // before its shadow starts to show.
            stats.count("depth_range", (r.far - r.near) as f64);
            stats.count(
                "offset_world",
                (offset / layout.span * (r.far - r.near)) as f64,
            );
        }
        stats.count("mip_levels", maps.mip_levels() as f64);
    }
}

impl ShadowTechnique for Convolution {
    fn name(&self) -> &'static str {
        "csm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("m".to_string(), self.m.into()),
            ("alpha".to_string(), param_value(self.alpha)),
            ("offset".to_string(), param_value(self.resolved_offset())),
            ("scale".to_string(), param_value(self.scale)),
            ("pivot".to_string(), param_value(self.pivot)),
            (
                "precision".to_string(),
                match self.precision {
                    Precision::U8 => "u8",
                    Precision::F32 => "f32",
                }
                .into(),
            ),
        ]);
        self.filtering.params(&mut m);
        m
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        in_key_order([OWN, &FilterSettings::SPECS].concat())
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "csm";
        let spec = find_param(t, &self.param_specs(), key)?;
        if self.filtering.set_param(t, key, value)? {
            return Ok(());
        }
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "m" => self.m = spec.u32(t, value)?,
            "alpha" => self.alpha = spec.f32(t, value)?,
            "offset" => {
                self.offset = if value.trim().eq_ignore_ascii_case("auto") {
                    None
                } else {
                    Some(spec.f32(t, value)?)
                }
            }
            "scale" => self.scale = spec.f32(t, value)?,
            "pivot" => self.pivot = spec.f32(t, value)?,
            "precision" => {
                self.precision = match value.trim().to_ascii_lowercase().as_str() {
                    "u8" | "8" | "8bit" => Precision::U8,
                    "f32" | "32" | "float" => Precision::F32,
                    _ => {
                        return Err(Error::param(format!(
                    "csm.precision = {value:?}: use u8 (8-bit basis images, the paper's) or f32"
                )))
                    }
                }
            }
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        check_resolution("csm", self.resolution)?;
        let mut stats = Stats::default();
        let value = match self.precision {
            Precision::U8 => self.run::<u8>(frame, &mut stats)?,
            Precision::F32 => self.run::<f32>(frame, &mut stats)?,
        };
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
