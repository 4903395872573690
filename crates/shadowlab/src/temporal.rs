//! Temporal error: how much a technique's shadow term changes from one frame to the next
//! beyond what the reference's changes — shimmering edges, swimming texels, cascade pops —
//! measured by reprojection.
//!
//! Reprojection ([`Reprojection::between`]): each covered pixel `k` of frame t has a world
//! position `p`; projected with frame t−1's camera it lands in pixel `k′` (the pixel whose
//! square holds the projected point). The pixel is *visible in both* frames when `k′` lies
//! in the image and is covered, shows the same triangle as `k`, and the surface point of
//! `k′` lies within one pixel footprint of `p` (`|dp/dx| + |dp/dy|` of `k′`, twice the
//! largest distance on one plane between a point and the centre of the pixel it projects
//! into) plus [`DEPTH_TOLERANCE`] of its view depth. On one triangle the test fails only
//! for geometry that moved; a point hidden in frame t−1 shows another triangle there.
//!
//! Temporal error ([`Reprojection::temporal_error`]): over the pixels visible in both,
//! the mean of `|Δv − Δv_ref|`, where `Δv = v_t(k) − v_{t−1}(k′)` is the change of the
//! technique's shadow term (luminance, 0–1) and `Δv_ref` the reference's at the same two
//! samples. A shadow that moves as the true one does, and an error that stays put on the
//! surface, cost nothing; a shadow that flickers where the reference holds still costs
//! its flicker. A technique that agrees with the reference in every pixel scores 0.

use crate::frame::{luminance, Visibility};
use crate::view::ViewSamples;
use rayon::prelude::*;

/// The surface point seen in frame t−1 may lie this share of its view depth further from
/// the reprojected point than the pixel footprint allows (floating-point rounding).
pub const DEPTH_TOLERANCE: f32 = 1e-4;

/// Marks a pixel of frame t that is not visible in frame t−1.
pub const NOT_VISIBLE: u32 = u32::MAX;

/// Where each pixel of frame t was in frame t−1.
#[derive(Clone, Debug)]
pub struct Reprojection {
    /// For each pixel of frame t, its pixel in frame t−1, or [`NOT_VISIBLE`].
    pub previous: Vec<u32>,
    /// Pixels visible in both frames.
    pub pixels: usize,
}

impl Reprojection {
    /// Reprojects every covered pixel of `current` into `previous` (the camera passes of
    /// two frames of one scene, of the same image size).
    pub fn between(previous: &ViewSamples, current: &ViewSamples) -> Self {
        assert_eq!(
            (previous.width, previous.height),
            (current.width, current.height),
            "frames of different sizes"
        );
        let clip = previous.camera.clip_from_world();
        let (w, h) = (previous.width as f32, previous.height as f32);
        let map: Vec<u32> = (0..current.triangle.len())
            .into_par_iter()
            .map(|k| {
                if !current.covered(k) {
                    return NOT_VISIBLE;
                }
                let p = current.position[k];
                let c = clip * p.extend(1.0);
                if c.w <= 0.0 || !c.is_finite() {
                    return NOT_VISIBLE;
                }
                let sx = (c.x / c.w * 0.5 + 0.5) * w;
                let sy = (0.5 - c.y / c.w * 0.5) * h;
                if !(sx >= 0.0 && sx < w && sy >= 0.0 && sy < h) {
                    return NOT_VISIBLE;
                }
                let kp = sy as usize * previous.width as usize + sx as usize;
                if previous.triangle[kp] != current.triangle[k] {
                    return NOT_VISIBLE;
                }
                let footprint = previous.dpdx[kp].length() + previous.dpdy[kp].length();
                let tolerance = footprint + DEPTH_TOLERANCE * previous.depth[kp].abs();
                if previous.position[kp].distance(p) > tolerance {
                    return NOT_VISIBLE;
                }
                kp as u32
            })
            .collect();
        let pixels = map.iter().filter(|&&kp| kp != NOT_VISIBLE).count();
        Reprojection {
            previous: map,
            pixels,
        }
    }

    /// The temporal error of a technique between frames t−1 and t (see the module
    /// documentation): its shadow terms `technique = [frame t−1, frame t]` against the
    /// reference's `reference = [frame t−1, frame t]`. `None` when no pixel is visible in
    /// both frames.
    pub fn temporal_error(
        &self,
        technique: [&Visibility; 2],
        reference: [&Visibility; 2],
    ) -> Option<f64> {
        if self.pixels == 0 {
            return None;
        }
        let [v0, v1] = technique;
        let [r0, r1] = reference;
        let mut sum = 0f64;
        for (k, &kp) in self.previous.iter().enumerate() {
            if kp == NOT_VISIBLE {
                continue;
            }
            let kp = kp as usize;
            let dv = luminance(v1.value[k]) - luminance(v0.value[kp]);
            let dr = luminance(r1.value[k]) - luminance(r0.value[kp]);
            sum += (dv - dr).abs() as f64;
        }
        Some(sum / self.pixels as f64)
    }
}
