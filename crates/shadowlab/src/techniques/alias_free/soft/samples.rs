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
//!
//! The samples are stored in Morton order of their frame coordinates, so every group of
//! [`GROUP`] consecutive samples covers a small patch of the light whose bounding box is
//! kept: a caster edge that misses a patch decides its whole group at once. The reference's
//! index of each stored sample is kept for the sums that must run in its order.

use crate::area_light::{concentric_disk, light_samples, orthonormal_basis, AreaLight};
use crate::math::{Vec2, Vec3};

/// Light samples per group: a quarter of a bitmask word.
pub(super) const GROUP: usize = 16;

/// All the bits of one group.
pub(super) const GROUP_BITS: u64 = (1 << GROUP) - 1;

/// A box `[x_lo, x_hi, y_lo, y_hi]` of frame coordinates.
pub(super) type FrameBox = [f32; 4];

/// The empty box.
pub(super) const EMPTY_BOX: FrameBox = [
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::INFINITY,
    f32::NEG_INFINITY,
];

/// The light samples and their frame coordinates.
#[derive(Clone, Debug)]
pub(super) struct LightSamples {
    /// The reference's sample positions in `[0, 1)²`, in storage (Morton) order.
    pub(super) uvs: Vec<Vec2>,
    /// Storage index of the reference's sample `k`.
    pub(super) stored: Vec<u32>,
    /// The box of each group's frame coordinates by bound (`x_lo`, `x_hi`, `y_lo`, `y_hi`
    /// of every group; zero for a group of padding alone), for passes over several groups
    /// at once.
    pub(super) group_bounds: [Vec<f32>; 4],
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
        let (xs, ys, ext): (Vec<f32>, Vec<f32>, f32) = match area {
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
        // Morton order of the coordinates quantized over the shape's extent (ties by index).
        let key = |i: usize| {
            let q = |c: f32| (((c / ext + 1.0) * 512.0) as u32).min(1023);
            (morton(q(xs[i]), q(ys[i])), i)
        };
        let mut order: Vec<usize> = (0..uvs.len()).collect();
        order.sort_unstable_by_key(|&i| key(i));
        let mut stored = vec![0u32; uvs.len()];
        for (s, &k) in order.iter().enumerate() {
            stored[k] = s as u32;
        }
        let uvs: Vec<Vec2> = order.iter().map(|&k| uvs[k]).collect();
        let mut xs: Vec<f32> = order.iter().map(|&k| xs[k]).collect();
        let mut ys: Vec<f32> = order.iter().map(|&k| ys[k]).collect();
        let group_box: Vec<FrameBox> = (0..uvs.len().div_ceil(64) * (64 / GROUP))
            .map(|g| {
                let end = ((g + 1) * GROUP).min(uvs.len());
                (g * GROUP..end).fold(EMPTY_BOX, |b, i| grow(b, xs[i], ys[i]))
            })
            .collect();
        let group_bounds = std::array::from_fn(|k| {
            group_box
                .iter()
                .map(|b| if b[0] <= b[1] { b[k] } else { 0.0 })
                .collect()
        });
        // Padded to whole words (the padding is never a live sample).
        let words = uvs.len().div_ceil(64);
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
            stored,
            group_bounds,
            xs,
            ys,
            ext,
            w,
        }
    }

    /// The box of group `g` (of real samples only: not one of padding alone).
    pub(super) fn group_box(&self, g: usize) -> FrameBox {
        self.group_bounds.each_ref().map(|b| b[g])
    }

    /// Number of samples.
    pub(super) fn len(&self) -> usize {
        self.uvs.len()
    }
}

/// `b` grown to hold `(x, y)`.
pub(super) fn grow(b: FrameBox, x: f32, y: f32) -> FrameBox {
    [b[0].min(x), b[1].max(x), b[2].min(y), b[3].max(y)]
}

/// The union of two boxes.
pub(super) fn union(a: FrameBox, b: FrameBox) -> FrameBox {
    [
        a[0].min(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].max(b[3]),
    ]
}

/// Interleaves the bits of two 10-bit coordinates.
fn morton(x: u32, y: u32) -> u32 {
    let spread = |v: u32| {
        let mut v = v & 0x3ff;
        v = (v | (v << 8)) & 0x00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    spread(x) | (spread(y) << 1)
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
