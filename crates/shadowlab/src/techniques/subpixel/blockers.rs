//! Blocker triangles of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps",
//! Section 3.4, Figure 6(a)): each triangle of a triangle–texel pair as three half-spaces
//! bounded by the planes through its edges and the light, plus its own plane, in the form
//! the visibility evaluation turns into half-planes on the screen.

use super::ray_plane::RayPlane;
use super::silhouette_edges::Toward;
use crate::math::Vec3;

/// Plane normals more nearly parallel than this (sine of the angle) to the direction they
/// are tested against are degenerate: a triangle seen edge-on from the light casts no area.
const EDGE_ON_SINE: f32 = 1e-6;

/// One blocker triangle with its four planes in screen-ready form.
pub(super) struct Blocker {
    /// The triangle's index in the scene.
    pub(super) tri: u32,
    /// Its vertices.
    pub(super) v: [Vec3; 3],
    /// Per plane its plane part (see the `ray_plane` module; `(m·(eye − q), m·dx, m·dy,
    /// m·d0)` under a perspective camera) for the plane `m·(X − q) ≥ 0`: three shadow-volume edge planes (inside ≥ 0), then the triangle's
    /// plane (≥ 0 behind the triangle as seen from the light).
    pub(super) planes: [[f32; 4]; 4],
}

impl Blocker {
    /// `None` for a triangle that casts no area (degenerate, or edge-on to the light).
    pub(super) fn new(tri: u32, v: [Vec3; 3], toward: &Toward, rays: &RayPlane) -> Option<Self> {
        let plane = |m: Vec3, q: Vec3| rays.plane(m, q);
        let [a, b, c] = v;
        let mut m4 = (b - a).cross(c - a);
        let ta = toward.at(a);
        let side = m4.dot(ta);
        if side.is_nan() || side.abs() <= EDGE_ON_SINE * m4.length() * ta.length() {
            return None;
        }
        if side > 0.0 {
            m4 = -m4;
        }
        let mut planes = [[0.0; 4]; 4];
        for (j, (p, q, r)) in [(a, b, c), (b, c, a), (c, a, b)].into_iter().enumerate() {
            // The neighbour across this edge must get the bit-identical plane, negated: derive
            // it from the edge's endpoints in a fixed order, whichever triangle asks.
            let (p, q) = if p.to_array() < q.to_array() {
                (p, q)
            } else {
                (q, p)
            };
            let mut m = (q - p).cross(toward.at(p));
            let s = m.dot(r - p);
            if s.is_nan() || s.abs() <= EDGE_ON_SINE * m.length() * (r - p).length() {
                return None;
            }
            if s < 0.0 {
                m = -m;
            }
            planes[j] = plane(m, p);
        }
        planes[3] = plane(m4, a);
        Some(Blocker { tri, v, planes })
    }
}
