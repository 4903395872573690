//! Vectors, matrices (named destination-from-source: `clip_from_world`), bounds and the
//! exact geometric predicates shared by the rasterizer, the reference and the techniques.

pub use glam::{vec2, vec3, vec4, DMat4, DVec3, DVec4, Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

/// Texture coordinates `(u, v)` in `[0, 1]²` (v down) of a clip-space position: the
/// perspective divide, then NDC `[-1, 1]` to `[0, 1]` with y flipped, as every light-space
/// map of shadowlab is addressed.
#[inline]
pub fn ndc_to_uv(clip: Vec4) -> (f32, f32) {
    (clip.x / clip.w * 0.5 + 0.5, 0.5 - clip.y / clip.w * 0.5)
}

/// The largest coordinate a camera or a light may have (1e18): the squared distance of
/// two points this far out still fits in `f32` (whose largest value is 3.4e38), so a
/// view direction or a distance computed from them is finite.
pub const MAX_COORDINATE: f32 = 1e18;

/// True when every component of `v` lies within ±[`MAX_COORDINATE`].
pub fn within_coordinate_limit(v: Vec3) -> bool {
    v.abs().max_element() <= MAX_COORDINATE
}

/// The unit vector along `v`, without overflow or underflow: scaled by its largest
/// component first, so `(3e38, 3e38, 3e38)` gives the diagonal where `normalize` (whose
/// squared length overflows) gives zero or NaN. `None` for a zero or non-finite `v`.
pub fn direction(v: Vec3) -> Option<Vec3> {
    let largest = v.abs().max_element();
    if !(largest.is_finite() && largest > 0.0) {
        return None;
    }
    let u = (v / largest).normalize();
    u.is_finite().then_some(u)
}

/// An axis-aligned bounding box. The empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (grows to the first point added).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box around `points`.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Self {
        let mut b = Self::EMPTY;
        for p in points {
            b.grow(*p);
        }
        b
    }

    /// Grows the box to hold `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The union of two boxes.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when nothing was added.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            vec3(a.x, a.y, a.z),
            vec3(b.x, a.y, a.z),
            vec3(a.x, b.y, a.z),
            vec3(b.x, b.y, a.z),
            vec3(a.x, a.y, b.z),
            vec3(b.x, a.y, b.z),
            vec3(a.x, b.y, b.z),
            vec3(b.x, b.y, b.z),
        ]
    }
}

/// pbrt's γ(n) = nε/(1−nε): a bound on the relative error of n floating-point operations.
pub fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5 * n as f32;
    e / (1.0 - e)
}

/// A ray–triangle hit: distance and barycentrics of `v0, v1, v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Distance along the ray (in units of the direction's length).
    pub t: f32,
    /// Barycentric weights of the three vertices.
    pub b: [f32; 3],
}

/// Watertight ray–triangle intersection (Woop, Benthin & Wald 2013): no ray passes
/// between two triangles that share an edge, and the answer is a pure function of the
/// inputs, so the BVH reference and a brute-force loop agree exactly. Hits with
/// `t` outside `(t_min, t_max)` are rejected. Both faces are hit.
#[inline]
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
    t_max: f32,
    v: [Vec3; 3],
) -> Option<TriangleHit> {
    intersect_sheared(origin, RayShear::new(dir), t_min, t_max, v)
}

/// The per-ray half of the watertight test: the axis permutation and the shear that map a
/// ray direction to +z. A caller testing one ray against many triangles may form it once
/// (and store it compactly) and call [`intersect_sheared`] per triangle.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    /// Axis permutation `kx, ky, kz`: `kz` is the direction's largest component.
    pub k: [usize; 3],
    /// Shear constants `sx, sy, sz`.
    pub s: [f32; 3],
}

impl RayShear {
    /// The permutation and shear of direction `dir`.
    #[inline]
    pub fn new(dir: Vec3) -> Self {
        // Permute axes so that the ray's largest direction component is z.
        let kz = dir.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        let sx = dir[kx] * sz;
        let sy = dir[ky] * sz;
        RayShear {
            k: [kx, ky, kz],
            s: [sx, sy, sz],
        }
    }
}

/// The per-triangle half of [`intersect_triangle`], for the ray from `origin` whose
/// direction `shear` was formed from: the same floating-point operations, so the same
/// answer bit for bit.
#[inline]
pub fn intersect_sheared(
    origin: Vec3,
    shear: RayShear,
    t_min: f32,
    t_max: f32,
    v: [Vec3; 3],
) -> Option<TriangleHit> {
    let [kx, ky, kz] = shear.k;
    let [sx, sy, sz] = shear.s;
    let a = v[0] - origin;
    let b = v[1] - origin;
    let c = v[2] - origin;
    // Shear the vertices into the ray's space.
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let mut u = cx * by - cy * bx;
    let mut w = ax * cy - ay * cx;
    let mut x = bx * ay - by * ax;
    // Fall back to double precision on the edges, where f32 cannot decide the sign.
    if u == 0.0 || w == 0.0 || x == 0.0 {
        u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
        w = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
        x = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
    }
    if (u < 0.0 || w < 0.0 || x < 0.0) && (u > 0.0 || w > 0.0 || x > 0.0) {
        return None;
    }
    let det = u + w + x;
    if det == 0.0 {
        return None;
    }
    let az = sz * a[kz];
    let bz = sz * b[kz];
    let cz = sz * c[kz];
    let t_scaled = u * az + w * bz + x * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t > t_min && t < t_max) {
        return None;
    }
    Some(TriangleHit {
        t,
        b: [u * inv_det, w * inv_det, x * inv_det],
    })
}

/// Barycentric coordinates of the point where the line `origin + t·dir` meets the plane of
/// the triangle, with no inside test (the rasterizer already decided coverage).
/// Returns `None` when the line is parallel to the plane.
pub fn intersect_plane(origin: Vec3, dir: Vec3, v: [Vec3; 3]) -> Option<TriangleHit> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - v[0];
    let b1 = s.dot(p) * inv;
    let q = s.cross(e1);
    let b2 = dir.dot(q) * inv;
    let t = e2.dot(q) * inv;
    Some(TriangleHit {
        t,
        b: [1.0 - b1 - b2, b1, b2],
    })
}

/// A point on a surface with a conservative bound on its floating-point error, so a ray
/// leaving it can be offset just past the error (pbrt's `OffsetRayOrigin`) instead of by a
/// fixed epsilon that depends on the scene's units.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The point.
    pub p: Vec3,
    /// Per-axis absolute error bound of `p`.
    pub error: Vec3,
}

impl SurfacePoint {
    /// The point at barycentrics `b` of triangle `v`, with pbrt's error bound
    /// γ(7)·Σ|bᵢvᵢ|, widened to cover barycentrics computed from an intersection.
    pub fn from_barycentrics(v: [Vec3; 3], b: [f32; 3]) -> Self {
        let p = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
        let mag = (v[0] * b[0]).abs() + (v[1] * b[1]).abs() + (v[2] * b[2]).abs();
        // The barycentrics themselves carry a few ulps of error relative to the vertex
        // magnitudes; γ(16) on the vertex magnitudes covers it.
        let vmag = v[0].abs().max(v[1].abs()).max(v[2].abs());
        SurfacePoint {
            p,
            error: mag * gamma(7) + vmag * gamma(16),
        }
    }

    /// A ray origin offset from the surface along `n` (unit face normal) towards `w`,
    /// far enough that the ray cannot re-hit the surface it leaves.
    pub fn offset_origin(&self, n: Vec3, w: Vec3) -> Vec3 {
        let d = n.abs().dot(self.error);
        let mut offset = n * d;
        if w.dot(n) < 0.0 {
            offset = -offset;
        }
        let mut po = self.p + offset;
        // Round away from p so the offset is not lost to rounding.
        for i in 0..3 {
            if offset[i] > 0.0 {
                po[i] = po[i].next_up();
            } else if offset[i] < 0.0 {
                po[i] = po[i].next_down();
            }
        }
        po
    }
}

/// Sign-exact 2D orientation of integer points: twice the signed area of (a, b, c).
#[inline]
pub fn orient2d_i64(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The view helpers, written once for `f32` and `f64` ([`pick_up`], [`look_along_rh`];
/// [`pick_up_f64`], [`look_along_rh_f64`]).
macro_rules! view_helpers {
    ($pick_up:ident, $look_along:ident, $float:ty, $v3:ty, $v4:ident, $m4:ty) => {
        /// An up vector for a view looking along `dir` that is not parallel to it: +Y, or +Z
        /// when `dir` is within about 8° of vertical.
        pub fn $pick_up(dir: $v3) -> $v3 {
            /// The vertical component of the unit `dir` above which +Y is too close to it.
            const VERTICAL: $float = 0.99;
            if dir.normalize().y.abs() > VERTICAL {
                <$v3>::Z
            } else {
                <$v3>::Y
            }
        }

        /// World-to-view matrix of an eye at `eye` looking along `forward` (any length):
        /// right-handed view space, looking down −Z with `up` towards +Y.
        pub fn $look_along(eye: $v3, forward: $v3, up: $v3) -> $m4 {
            let f = forward.normalize();
            let s = f.cross(up).normalize();
            let u = s.cross(f);
            <$m4>::from_cols(
                $v4::new(s.x, u.x, -f.x, 0.0),
                $v4::new(s.y, u.y, -f.y, 0.0),
                $v4::new(s.z, u.z, -f.z, 0.0),
                $v4::new(-eye.dot(s), -eye.dot(u), eye.dot(f), 1.0),
            )
        }
    };
}

view_helpers!(pick_up, look_along_rh, f32, Vec3, Vec4, Mat4);
view_helpers!(pick_up_f64, look_along_rh_f64, f64, DVec3, DVec4, DMat4);

/// World-to-view matrix of an eye at `eye` looking at `target`: right-handed view space,
/// looking down −Z with +Y up.
pub fn look_at_rh(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    look_along_rh(eye, target - eye, up)
}

/// Far planes lie this factor beyond the farthest depth of what a view is fitted to.
pub const FAR_MARGIN: f32 = 1.01;
/// Near planes lie this factor in front of the nearest depth, when all of it is in front.
pub const NEAR_MARGIN: f32 = 0.99;
/// When some of what a view is fitted to is behind its eye plane, near is this share of far.
pub const NEAR_SHARE_INSIDE: f32 = 1e-4;
/// Near is never less than this share of far, which bounds the depth range's ratio.
pub const MIN_NEAR_SHARE: f32 = 1e-5;

/// The `(near, far)` planes of a view fitted to points at the view depths `depths`: far
/// just beyond the farthest ([`FAR_MARGIN`], at least `min_far`), near just in front of the
/// nearest ([`NEAR_MARGIN`]) or, when some point is behind the eye plane, a small share of
/// far ([`NEAR_SHARE_INSIDE`]); never below [`MIN_NEAR_SHARE`] of far.
pub fn fit_near_far(depths: impl IntoIterator<Item = f32>, min_far: f32) -> (f32, f32) {
    let mut zmin = f32::INFINITY;
    let mut zmax = f32::NEG_INFINITY;
    for z in depths {
        zmin = zmin.min(z);
        zmax = zmax.max(z);
    }
    let far = (zmax * FAR_MARGIN).max(min_far);
    let near = if zmin > 0.0 {
        zmin * NEAR_MARGIN
    } else {
        far * NEAR_SHARE_INSIDE
    };
    (near.max(far * MIN_NEAR_SHARE), far)
}

/// View-to-clip perspective projection (right-handed view space, depth in `[0, 1]`, clip
/// `w` = view depth). `fov_y` in radians.
pub fn perspective_rh(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    let w = h / aspect;
    let r = far / (near - far);
    Mat4::from_cols(
        vec4(w, 0.0, 0.0, 0.0),
        vec4(0.0, h, 0.0, 0.0),
        vec4(0.0, 0.0, r, -1.0),
        vec4(0.0, 0.0, r * near, 0.0),
    )
}

/// View-to-clip orthographic projection (right-handed view space, depth in `[0, 1]`).
pub fn orthographic_rh(left: f32, right: f32, bottom: f32, top: f32, near: f32, far: f32) -> Mat4 {
    let rw = 1.0 / (right - left);
    let rh = 1.0 / (top - bottom);
    let r = 1.0 / (near - far);
    Mat4::from_cols(
        vec4(2.0 * rw, 0.0, 0.0, 0.0),
        vec4(0.0, 2.0 * rh, 0.0, 0.0),
        vec4(0.0, 0.0, r, 0.0),
        vec4(-(left + right) * rw, -(top + bottom) * rh, r * near, 1.0),
    )
}

/// A tiny seeded generator for the library's unit tests (no extra crate, same sequence
/// on every machine).
#[cfg(test)]
pub(crate) struct TestRng(pub(crate) u64);

#[cfg(test)]
impl TestRng {
    /// Uniform in [0, 1).
    pub(crate) fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Uniform in [-1, 1)³.
    pub(crate) fn v(&mut self) -> Vec3 {
        vec3(self.next(), self.next(), self.next()) * 2.0 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_scaled_before_they_are_normalized() {
        let d = direction(vec3(3e38, 3e38, 3e38)).unwrap();
        assert!((d - Vec3::splat(1.0 / 3f32.sqrt())).abs().max_element() < 1e-6);
        let tiny = direction(vec3(1e-30, 0.0, 0.0)).unwrap();
        assert_eq!(tiny, Vec3::X);
        assert!(direction(Vec3::ZERO).is_none());
        assert!(direction(vec3(f32::INFINITY, 0.0, 0.0)).is_none());
    }

    #[test]
    fn watertight_shared_edge_is_hit_once_or_twice_never_missed() {
        // Rays through the shared diagonal of a quad must hit at least one triangle.
        let q = [
            vec3(0.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
            vec3(1.0, 1.0, 0.0),
            vec3(0.0, 1.0, 0.0),
        ];
        for i in 0..1000 {
            let s = i as f32 / 1000.0;
            let o = vec3(s, s, 1.0);
            let d = vec3(0.0, 0.0, -1.0);
            let a = intersect_triangle(o, d, 0.0, f32::INFINITY, [q[0], q[1], q[2]]);
            let b = intersect_triangle(o, d, 0.0, f32::INFINITY, [q[0], q[2], q[3]]);
            assert!(a.is_some() || b.is_some(), "ray {s} slipped through");
        }
    }

    #[test]
    fn plane_intersection_matches_triangle_intersection_inside() {
        let v = [
            vec3(0.0, 0.0, 0.0),
            vec3(2.0, 0.0, 0.0),
            vec3(0.0, 2.0, 1.0),
        ];
        let o = vec3(0.3, 0.4, 5.0);
        let d = vec3(0.01, -0.02, -1.0);
        let a = intersect_triangle(o, d, 0.0, f32::INFINITY, v).unwrap();
        let b = intersect_plane(o, d, v).unwrap();
        assert!((a.t - b.t).abs() < 1e-5);
    }
}
