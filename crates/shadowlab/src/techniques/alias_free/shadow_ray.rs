//! The exact per-sample test of alias-free shadow maps (Aila & Laine 2004): each sample's
//! shadow ray, set up once for the watertight ray–triangle test of
//! [`crate::math::intersect_triangle`].
//!
//! The paper decides a covered sample by comparing the triangle's depth with the sample's
//! light-space depth and notes that only floating-point error separates that from tracing a
//! shadow ray; here the leaves trace that very ray instead, so the answer is the
//! reference's bit for bit.

use crate::math::{intersect_sheared, RayShear, Vec3};

/// A sample's shadow ray, pre-sheared for the watertight test.
#[derive(Clone, Copy, Debug)]
pub(super) struct ShadowRay {
    /// Ray origin (the offset surface point).
    pub(super) o: [f32; 3],
    /// Shear constants `sx, sy, sz` of the watertight test.
    s: [f32; 3],
    /// Length of the segment to the light (infinite for a directional light).
    t_max: f32,
    /// Axis permutation `kx, ky, kz` (stored in bytes: one ray per sample).
    k: [u8; 3],
    /// The triangle the sample lies on (never its own occluder).
    pub(super) own: u32,
    /// Where the sample's shadow term goes: its screen pixel, or, past the last pixel,
    /// its layer sample (`pixels + i` for layer sample `i`).
    pub(super) pixel: u32,
}

impl ShadowRay {
    /// The ray `o + t·dir`, `t ∈ (0, t_max)`, with the set-up of
    /// [`crate::math::intersect_triangle`].
    pub(super) fn new(o: Vec3, dir: Vec3, t_max: f32, own: u32, pixel: u32) -> Self {
        Self::sheared(o, RayShear::new(dir), t_max, own, pixel)
    }

    /// [`Self::new`] for a direction whose shear is formed already (every ray of a
    /// directional light shares one).
    #[inline]
    pub(super) fn sheared(o: Vec3, shear: RayShear, t_max: f32, own: u32, pixel: u32) -> Self {
        let RayShear { k, s } = shear;
        ShadowRay {
            o: o.to_array(),
            s,
            t_max,
            k: k.map(|k| k as u8),
            own,
            pixel,
        }
    }

    /// True when the ray hits triangle `v` strictly between its ends: the same answer, from
    /// the same floating-point operations, as `intersect_triangle(o, dir, 0, t_max, v)`.
    #[cfg(test)]
    pub(super) fn hits(&self, v: [Vec3; 3]) -> bool {
        self.hit(v).is_some()
    }

    /// [`Self::hits`] with the hit's barycentrics, the same bits as the reference's.
    #[inline]
    pub(super) fn hit(&self, v: [Vec3; 3]) -> Option<[f32; 3]> {
        let shear = RayShear {
            k: self.k.map(usize::from),
            s: self.s,
        };
        intersect_sheared(Vec3::from_array(self.o), shear, 0.0, self.t_max, v).map(|h| h.b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::intersect_triangle;
    use crate::math::TestRng as Lcg;

    #[test]
    fn presheared_ray_test_is_the_watertight_test() {
        let mut rng = Lcg(11);
        let mut hits = 0;
        for i in 0..200_000 {
            let o = rng.v() * 3.0;
            // Directions along the axes and with negative components exercise every shear
            // permutation and the f64 fallback on exact edge hits.
            let mut dir = rng.v().normalize();
            if i % 7 == 0 {
                dir = [Vec3::X, -Vec3::Y, Vec3::Z][i % 3];
            }
            let t_max = if i % 2 == 0 {
                f32::INFINITY
            } else {
                rng.next() * 4.0
            };
            let c = o + dir * (rng.next() * 3.0);
            let v = if i % 5 == 0 {
                // A triangle with an edge through the ray's point of passage.
                let a = c + rng.v();
                [a, c + (c - a), c + rng.v()]
            } else {
                [c + rng.v(), c + rng.v(), c + rng.v()]
            };
            let exact = intersect_triangle(o, dir, 0.0, t_max, v).is_some();
            let ray = ShadowRay::new(o, dir, t_max, 0, 0);
            assert_eq!(ray.hits(v), exact, "case {i}");
            hits += exact as u32;
        }
        assert!(hits > 10_000);
    }
}
