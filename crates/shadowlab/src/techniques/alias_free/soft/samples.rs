//! The light samples of exact soft alias-free shadows, in the coordinates the bitmask
//! classification works in: every light sample `i` is the point (or, for a distant light,
//! the direction) `A + xᵢ·U + yᵢ·V` of an affine frame of the light's emitting shape, so
//! the plane through a view sample and a caster edge is an affine function of `(xᵢ, yᵢ)`
//! and one pass over two arrays classifies all `N` samples against it.
//!
//! The samples are those of [`crate::area_light::light_samples`] (the reference's own set);
//! the frame is the shape's: a rectangle's centre and edges with `x, y = u − ½, v − ½`, a
//! disk's centre and radius-scaled basis with `(x, y)` the concentric map, a sphere's
//! cross-section facing the point (its basis moves with the point, the coordinates do
//! not), a distant light's axis and the tangent-scaled basis about it. The frame
//! reproduces each sample's position up to a few roundings, which the classification's
//! margins cover; the decision in the uncertain band is the reference's own ray.

use crate::area_light::{concentric_disk, light_samples, orthonormal_basis, AreaLight};
use crate::math::{Vec2, Vec3};

/// The light samples and their frame coordinates.
#[derive(Clone, Debug)]
pub(super) struct LightSamples {
    /// The reference's sample positions in `[0, 1)²`.
    pub(super) uvs: Vec<Vec2>,
    /// Frame coordinates of each sample, padded with zeros to whole words.
    pub(super) xs: Vec<f32>,
    pub(super) ys: Vec<f32>,
    /// Bitmask words per view sample: ⌈N / 64⌉.
    pub(super) words: usize,
    /// Largest |x| and |y| over the shape (½ for a rectangle, 1 for the disk shapes).
    pub(super) ext: f32,
    /// 1 when the frame places points, 0 when it places directions (a distant light).
    pub(super) w: f32,
}

/// The light's affine frame as seen from one point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Frame3 {
    pub(super) a: Vec3,
    pub(super) u: Vec3,
    pub(super) v: Vec3,
}

impl LightSamples {
    /// The first `n` samples of the reference's set under `area`.
    pub(super) fn new(area: &AreaLight, n: u32) -> LightSamples {
        let uvs = light_samples(n);
        let (xs, ys, ext) = match area {
            AreaLight::Rect { .. } => (
                uvs.iter().map(|p| p.x - 0.5).collect(),
                uvs.iter().map(|p| p.y - 0.5).collect(),
                0.5,
            ),
            _ => {
                let d: Vec<Vec2> = uvs.iter().map(|&p| concentric_disk(p)).collect();
                (
                    d.iter().map(|p| p.x).collect(),
                    d.iter().map(|p| p.y).collect(),
                    1.0,
                )
            }
        };
        // Padded to whole words (the padding is never a live sample).
        let words = uvs.len().div_ceil(64);
        let (mut xs, mut ys): (Vec<f32>, Vec<f32>) = (xs, ys);
        xs.resize(words * 64, 0.0);
        ys.resize(words * 64, 0.0);
        let w = if matches!(area, AreaLight::Distant { .. }) {
            0.0
        } else {
            1.0
        };
        LightSamples {
            words,
            uvs,
            xs,
            ys,
            ext,
            w,
        }
    }

    /// Number of samples.
    pub(super) fn len(&self) -> usize {
        self.uvs.len()
    }
}

/// The frame of `area` as seen from `p` (only a sphere's depends on `p`).
pub(super) fn frame_at(area: &AreaLight, p: Vec3) -> Frame3 {
    match *area {
        AreaLight::Rect {
            centre,
            edge_u,
            edge_v,
        } => Frame3 {
            a: centre,
            u: edge_u,
            v: edge_v,
        },
        AreaLight::Disk {
            centre,
            normal,
            radius,
        } => {
            let (a, b) = orthonormal_basis(normal);
            Frame3 {
                a: centre,
                u: a * radius,
                v: b * radius,
            }
        }
        AreaLight::Sphere { centre, radius } => {
            // As `AreaLight::position` turns the cross-section towards the point.
            let w = (p - centre).normalize_or_zero();
            let w = if w == Vec3::ZERO { Vec3::Y } else { w };
            let (a, b) = orthonormal_basis(w);
            Frame3 {
                a: centre,
                u: a * radius,
                v: b * radius,
            }
        }
        AreaLight::Distant { to_light, .. } => {
            let (a, b) = orthonormal_basis(to_light);
            let r = area.radius();
            Frame3 {
                a: to_light,
                u: a * r,
                v: b * r,
            }
        }
    }
}

/// Points (directions for a distant light) whose convex hull holds every sample of
/// `area` from every point: the rectangle's corners, the square about a disk or a distant
/// light's disk, the cube about a sphere.
pub(super) fn bounding_corners(area: &AreaLight) -> Vec<Vec3> {
    let signs = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    match *area {
        AreaLight::Sphere { centre, radius } => (0..8)
            .map(|i| {
                let s = |b: u32| if i & (1 << b) != 0 { radius } else { -radius };
                centre + Vec3::new(s(0), s(1), s(2))
            })
            .collect(),
        AreaLight::Rect { .. } => {
            let f = frame_at(area, Vec3::ZERO);
            signs
                .iter()
                .map(|&(x, y)| f.a + f.u * (0.5 * x) + f.v * (0.5 * y))
                .collect()
        }
        _ => {
            let f = frame_at(area, Vec3::ZERO);
            signs
                .iter()
                .map(|&(x, y)| f.a + f.u * x + f.v * y)
                .collect()
        }
    }
}
