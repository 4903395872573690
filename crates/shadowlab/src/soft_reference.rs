//! The ground truth under an area light: per pixel, the fraction of the light's emitting
//! area that the visible point sees, each light sample weighted by the RGB transmittance
//! of the casters towards it (see [`crate::area_light`]), and the estimate's own standard
//! error.
//!
//! Every pixel takes the same fixed, stratified low-discrepancy set of `N` light samples
//! ([`crate::area_light::light_samples`]); shadow rays are traced through the reference's
//! BVH exactly as for a punctual light (error-bounded origin offset, own triangle
//! skipped). With supersampled primary rays, sub-pixel sample `j` of `spp` takes the
//! `j`-th aligned block of the light samples, so a pixel costs `max(N, spp)` shadow rays
//! and the blocks together are the whole set; with fewer light samples than primary rays
//! each primary ray takes one sample in turn.
//!
//! The standard error of a pixel treats its `M` shadow-ray values (luminance of the
//! transmittance) as independent: `sqrt(Σ(x − x̄)² / (M (M − 1)))`. The samples are
//! stratified, so the true error is at most this (usually well below it): a verdict that
//! states it states an upper bound on the reference's own noise.
//!
//! Results are the same bits for any thread count: each pixel is computed alone, and its
//! sums are taken in sample order.

use crate::area_light::{light_samples, AreaLight};
use crate::frame::{luminance, Frame, Visibility};
use crate::light::Light;
use crate::math::{SurfacePoint, Vec2, Vec3};
use crate::reference::{facing_normal, Reference};
use rayon::prelude::*;

/// The soft-shadow reference of a frame and its per-pixel standard error.
#[derive(Clone, Debug)]
pub struct SoftReference {
    /// The shadow term.
    pub visibility: Visibility,
    /// Per pixel, the standard error of the shadow term's luminance (0 where uncovered).
    pub std_error: Vec<f32>,
}

impl SoftReference {
    /// Mean standard error over the covered pixels of `frame`.
    pub fn mean_std_error(&self, frame: &Frame) -> f64 {
        let view = frame.view;
        let covered = view.covered_count().max(1);
        let sum: f64 = (0..self.std_error.len())
            .filter(|&k| view.covered(k))
            .map(|k| self.std_error[k] as f64)
            .sum();
        sum / covered as f64
    }

    /// Mean of the squared standard errors (the estimate's variance) over covered pixels.
    pub fn mean_variance(&self, frame: &Frame) -> f64 {
        let view = frame.view;
        let covered = view.covered_count().max(1);
        let sum: f64 = (0..self.std_error.len())
            .filter(|&k| view.covered(k))
            .map(|k| (self.std_error[k] as f64).powi(2))
            .sum();
        sum / covered as f64
    }
}

/// Running sums of one pixel's shadow-ray values.
#[derive(Clone, Copy, Default)]
struct Sums {
    rgb: Vec3,
    lum: f64,
    lum2: f64,
    count: u32,
}

impl Sums {
    fn add(&mut self, t: Vec3) {
        let l = luminance(t) as f64;
        self.rgb += t;
        self.lum += l;
        self.lum2 += l * l;
        self.count += 1;
    }

    fn merge(&mut self, o: &Sums) {
        self.rgb += o.rgb;
        self.lum += o.lum;
        self.lum2 += o.lum2;
        self.count += o.count;
    }

    fn mean(&self) -> Vec3 {
        self.rgb / self.count.max(1) as f32
    }

    fn std_error(&self) -> f32 {
        if self.count < 2 {
            return 0.0;
        }
        let m = self.count as f64;
        let mean = self.lum / m;
        let ss = (self.lum2 - m * mean * mean).max(0.0);
        (ss / (m * (m - 1.0))).sqrt() as f32
    }
}

/// Whether light sample `uv` of `area` lights the point `sp` (unit normal `n` turned towards
/// the viewer): `None` when the sample lies behind the surface, else the shadow ray's
/// origin, direction and length. The exact soft technique forms its rays the same way.
pub fn shadow_ray(
    area: &AreaLight,
    sp: &SurfacePoint,
    n: Vec3,
    uv: Vec2,
) -> Option<(Vec3, Vec3, f32)> {
    let lp = area.sample_from(sp.p, uv);
    let cos = n.dot(lp.dir);
    if cos.is_nan() || cos <= 0.0 {
        return None;
    }
    let o = sp.offset_origin(n, lp.dir);
    if lp.dist.is_infinite() {
        return Some((o, lp.dir, f32::INFINITY));
    }
    let d = area.position(sp.p, uv) - o;
    let len = d.length();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    Some((o, d / len, len))
}

/// The light samples that sub-pixel sample `j` of `spp` takes out of `n`: an aligned
/// block, or one sample in turn when there are fewer light samples than primary rays.
pub fn block(j: usize, spp: usize, n: usize) -> std::ops::Range<usize> {
    if n >= spp {
        j * n / spp..(j + 1) * n / spp
    } else {
        let i = j % n;
        i..i + 1
    }
}

impl Reference<'_> {
    /// Adds to `sums` the transmittance towards each light sample of `uvs` from the surface
    /// point `sp` on triangle `own` (0 for samples behind the surface, and for every sample
    /// when `stand_in`'s cone leaves the point out).
    fn area_sums(
        &self,
        area: &AreaLight,
        stand_in: &Light,
        hit: (&SurfacePoint, Vec3, u32),
        uvs: &[Vec2],
        sums: &mut Sums,
    ) {
        let (sp, n, own) = hit;
        let in_cone = AreaLight::in_cone(stand_in, sp.p);
        for &uv in uvs {
            let t = match shadow_ray(area, sp, n, uv) {
                Some((o, dir, t_max)) if in_cone => self.occlusion(o, dir, t_max, own),
                _ => Vec3::ZERO,
            };
            sums.add(t);
        }
    }
}

/// The soft-shadow reference of `frame` under `area` with `n_light` light samples per
/// pixel; `pixel_samples` as for [`Reference::visibility`] (one position traces from the
/// camera pass's samples).
pub fn soft_visibility(
    reference: &Reference,
    frame: &Frame,
    area: &AreaLight,
    n_light: u32,
    pixel_samples: &[Vec2],
) -> SoftReference {
    let view = frame.view;
    let scene = frame.scene;
    let rays = frame.camera.rays();
    let uvs = light_samples(n_light);
    let (w, h) = (view.width, view.height);
    let spp = pixel_samples.len();
    let rows: Vec<Vec<(Vec3, f32)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .map(|x| {
                    let k = (y * w + x) as usize;
                    if !view.covered(k) {
                        return (Vec3::ONE, 0.0);
                    }
                    let centre_hit = (&view.surface_point(k), view.normal[k], view.triangle[k]);
                    let mut centre = Sums::default();
                    if spp <= 1 {
                        reference.area_sums(area, frame.light, centre_hit, &uvs, &mut centre);
                        return (centre.mean(), centre.std_error());
                    }
                    let mut sums = Sums::default();
                    for (j, s) in pixel_samples.iter().enumerate() {
                        let (o, d) = rays.ray(x as f32 + s.x, y as f32 + s.y);
                        let Some(hit) = reference.closest_hit(o, d) else {
                            continue;
                        };
                        let n = facing_normal(scene, hit.triangle, d);
                        let mut one = Sums::default();
                        let block = &uvs[block(j, spp, uvs.len())];
                        let h = (&hit.point, n, hit.triangle);
                        reference.area_sums(area, frame.light, h, block, &mut one);
                        sums.merge(&one);
                    }
                    if sums.count == 0 {
                        reference.area_sums(area, frame.light, centre_hit, &uvs, &mut centre);
                        return (centre.mean(), centre.std_error());
                    }
                    (sums.mean(), sums.std_error())
                })
                .collect()
        })
        .collect();
    let (value, std_error) = rows.concat().into_iter().unzip();
    SoftReference {
        visibility: Visibility {
            width: w,
            height: h,
            value,
        },
        std_error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_partition_the_light_samples() {
        for (spp, n) in [(1, 256), (4, 256), (16, 256), (16, 100), (9, 4)] {
            let mut count = vec![0; n];
            for j in 0..spp {
                for i in block(j, spp, n) {
                    count[i] += 1;
                }
            }
            if n >= spp {
                assert!(count.iter().all(|&c| c == 1), "{spp} {n}");
            } else {
                assert!(count.iter().all(|&c| c >= 1), "{spp} {n}");
            }
        }
    }
}
