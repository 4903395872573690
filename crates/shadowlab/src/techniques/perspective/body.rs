//! The body `H` of `psm` (Stamminger & Drettakis 2002, Section 4.1, "Including all Objects
//! Casting Shadows — World Space"): every point that must appear in the shadow map, in
//! world space and in f64.
//!
//! `B` = view frustum `V` (its near and far planes pushed to the receivers, [`super::near_plane`])
//! ∩ box of the visible lit receivers ∩ light frustum `L` (a spot light's pyramid); then
//! `H = hull(B ∪ l) ∩ S` with `S` the scene bounds and `l` the light, a point at infinity
//! along `to_light` for a directional light. The paper computes it with CGAL; here it is an
//! exact convex polyhedron clipped plane by plane: the faces of `B` that do not face the
//! light, plus the planes through the light and `B`'s silhouette edges. Every caster
//! between a receiver and the light lies in `H`.

use super::fit::frame_of;
use super::near_plane::Receivers;
use crate::camera::Projection;
use crate::frame::Frame;
use crate::light::Light;
use crate::math::{pick_up_f64, Aabb, Vec3};
use glam::DVec3;

/// The box of visible receivers is widened by this fraction of the scene's diagonal on
/// each side: it covers the floating-point error of the receiver positions and keeps the
/// body solid when every receiver lies on one plane. Larger values waste texels.
pub const RECEIVER_PAD: f64 = 1e-4;
/// Polyhedron clipping treats points within this fraction of the scene's coordinate
/// magnitude as lying on a plane; planes of the body are pushed out by as much, so
/// rounding can only make the body larger.
const GEOMETRY_TOLERANCE: f64 = 1e-9;
/// The smallest coordinate magnitude the tolerance is taken of, so a scene of zeros (all at
/// the origin, camera included) still gets a positive tolerance.
const MIN_SCALE: f32 = 1e-30;
/// The tangents of the view frustum's and the spot cone's half-angles are widened by this
/// fraction, so rounding never cuts a visible or lit receiver off the body.
const TANGENT_WIDENING: f64 = 1e-6;
/// …and a spot cone's by this much more, absolutely, so a cone of a vanishing angle keeps a
/// pyramid with four distinct side planes.
const SPOT_TANGENT_SLACK: f64 = 1e-9;
/// A face of `B` whose outward normal has a cosine up to this with the direction towards a
/// directional light counts as facing away from it (edge-on faces are kept: they bound the
/// hull along the light's rays).
const EDGE_ON_COSINE: f64 = 1e-12;

/// A half-space `n · x <= d`.
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: DVec3,
    d: f64,
}

impl Plane {
    #[inline]
    fn dist(&self, p: DVec3) -> f64 {
        self.n.dot(p) - self.d
    }
}

/// A convex polyhedron as its face polygons.
#[derive(Clone, Debug, Default)]
struct Body {
    faces: Vec<Vec<DVec3>>,
}

/// Faces of a hexahedron whose corners are indexed like [`Aabb::corners`] (bit 0: +x,
/// bit 1: +y, bit 2: +z).
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 2, 6, 4],
    [1, 5, 7, 3],
    [0, 4, 5, 1],
    [2, 3, 7, 6],
    [0, 1, 3, 2],
    [4, 6, 7, 5],
];

impl Body {
    fn hexahedron(c: [DVec3; 8]) -> Body {
        Body {
            faces: HEX_FACES
                .iter()
                .map(|f| f.iter().map(|&i| c[i]).collect())
                .collect(),
        }
    }

    fn from_box(b: &Aabb, pad: f64) -> Body {
        let lo = b.min.as_dvec3() - DVec3::splat(pad);
        let hi = b.max.as_dvec3() + DVec3::splat(pad);
        Body::hexahedron(std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 != 0 { hi.x } else { lo.x },
                if i & 2 != 0 { hi.y } else { lo.y },
                if i & 4 != 0 { hi.z } else { lo.z },
            )
        }))
    }

    fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The distinct vertices.
    fn vertices(&self, tol: f64) -> Vec<DVec3> {
        let mut out: Vec<DVec3> = Vec::new();
        for f in &self.faces {
            for &p in f {
                if !out.iter().any(|q| (*q - p).abs().max_element() <= tol) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The part of the body with `plane.dist(x) <= tol`.
    fn clip(&self, plane: Plane, tol: f64) -> Body {
        let mut faces = Vec::with_capacity(self.faces.len() + 1);
        let mut cap: Vec<DVec3> = Vec::new();
        for f in &self.faces {
            let mut out: Vec<DVec3> = Vec::with_capacity(f.len() + 2);
            for i in 0..f.len() {
                let (a, b) = (f[i], f[(i + 1) % f.len()]);
                let (da, db) = (plane.dist(a), plane.dist(b));
                if da <= tol {
                    out.push(a);
                    if da >= -tol {
                        cap.push(a);
                    }
                }
                if (da < -tol && db > tol) || (da > tol && db < -tol) {
                    // From the inside vertex towards the outside one, so the two faces that
                    // share the edge get the same point.
                    let (pi, di, po, dout) = if da < 0.0 {
                        (a, da, b, db)
                    } else {
                        (b, db, a, da)
                    };
                    let p = pi + (po - pi) * (di / (di - dout));
                    out.push(p);
                    cap.push(p);
                }
            }
            out.dedup_by(|x, y| (*x - *y).abs().max_element() <= tol);
            if out.len() >= 3 {
                faces.push(out);
            }
        }
        let mut pts: Vec<DVec3> = Vec::new();
        for p in cap {
            if !pts.iter().any(|q| (*q - p).abs().max_element() <= tol) {
                pts.push(p);
            }
        }
        if pts.len() >= 3 && !faces.is_empty() {
            // Order the cap polygon by angle around its centroid in the plane.
            let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
            let u = plane.n.any_orthonormal_vector();
            let v = plane.n.cross(u);
            pts.sort_by(|a, b| {
                let aa = (*a - c).dot(v).atan2((*a - c).dot(u));
                let ab = (*b - c).dot(v).atan2((*b - c).dot(u));
                aa.total_cmp(&ab)
            });
            faces.push(pts);
        }
        Body { faces }
    }

    fn clip_all(&self, planes: &[Plane], tol: f64) -> Body {
        let mut b = self.clone();
        for p in planes {
            if b.is_empty() {
                break;
            }
            b = b.clip(*p, tol);
        }
        b
    }
}

/// The outward plane of a face of a body whose interior contains `inside`.
fn face_plane(face: &[DVec3], inside: DVec3) -> Option<Plane> {
    // Newell's method: robust for any planar polygon.
    let mut n = DVec3::ZERO;
    for i in 0..face.len() {
        let (a, b) = (face[i], face[(i + 1) % face.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let n = n.try_normalize()?;
    let c = face.iter().copied().sum::<DVec3>() / face.len() as f64;
    let n = if n.dot(inside - c) > 0.0 { -n } else { n };
    Some(Plane { n, d: n.dot(c) })
}

/// The light as a point, possibly at infinity.
#[derive(Clone, Copy, Debug)]
enum LightPoint {
    At(DVec3),
    /// At infinity in this (unit) direction.
    Towards(DVec3),
}

/// Half-spaces whose intersection is `hull(B ∪ l)`: the faces of `B` that do not face the
/// light, and the planes through the light and each silhouette edge of `B`. Each is
/// pushed out by `tol`, so the hull can only grow.
fn hull_planes(b: &Body, light: LightPoint, tol: f64) -> Vec<Plane> {
    let verts = b.vertices(tol);
    let inside = verts.iter().copied().sum::<DVec3>() / verts.len().max(1) as f64;
    let mut planes = Vec::new();
    for f in &b.faces {
        if let Some(pl) = face_plane(f, inside) {
            let keep = match light {
                LightPoint::At(l) => pl.dist(l) <= tol,
                LightPoint::Towards(d) => pl.n.dot(d) <= EDGE_ON_COSINE,
            };
            if keep {
                planes.push(Plane {
                    n: pl.n,
                    d: pl.d + tol,
                });
            }
        }
        for i in 0..f.len() {
            let (a, e) = (f[i], f[(i + 1) % f.len()]);
            if (e - a).length() <= tol {
                continue;
            }
            let m = match light {
                LightPoint::At(l) => (e - a).cross(l - a),
                LightPoint::Towards(d) => (e - a).cross(d),
            };
            let Some(m) = m.try_normalize() else { continue };
            let d = m.dot(a);
            let (lo, hi) = verts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    let s = m.dot(*v) - d;
                    (lo.min(s), hi.max(s))
                });
            if hi <= tol {
                planes.push(Plane { n: m, d: d + tol });
            } else if lo >= -tol {
                planes.push(Plane { n: -m, d: -d + tol });
            }
        }
    }
    planes
}

/// The four side planes of the square pyramid around a spot light's cone: the light
/// frustum `L`.
fn spot_planes(position: Vec3, target: Vec3, fov_deg: f32) -> [Plane; 4] {
    let l = position.as_dvec3();
    let axis = (target.as_dvec3() - l).normalize();
    let (right, up) = frame_of(axis, pick_up_f64(axis));
    // Slightly wider than the cone, so rounding never cuts a lit receiver off.
    let half =
        ((fov_deg as f64).to_radians() * 0.5).tan() * (1.0 + TANGENT_WIDENING) + SPOT_TANGENT_SLACK;
    [right, -right, up, -up].map(|s| {
        let n = (s - axis * half).normalize();
        Plane { n, d: n.dot(l) }
    })
}

/// The six planes of a box, pushed out by `pad`.
fn box_planes(b: &Aabb, pad: f64) -> [Plane; 6] {
    let (lo, hi) = (b.min.as_dvec3() - pad, b.max.as_dvec3() + pad);
    [
        Plane {
            n: DVec3::X,
            d: hi.x,
        },
        Plane {
            n: -DVec3::X,
            d: -lo.x,
        },
        Plane {
            n: DVec3::Y,
            d: hi.y,
        },
        Plane {
            n: -DVec3::Y,
            d: -lo.y,
        },
        Plane {
            n: DVec3::Z,
            d: hi.z,
        },
        Plane {
            n: -DVec3::Z,
            d: -lo.z,
        },
    ]
}

/// The distance under which two points of the frame's bodies count as one:
/// [`GEOMETRY_TOLERANCE`] of the largest coordinate of the scene and the eye.
pub(super) fn geometry_tolerance(frame: &Frame) -> f64 {
    let scene = &frame.scene.bounds;
    let scale = scene
        .min
        .abs()
        .max(scene.max.abs())
        .max_element()
        .max(frame.camera.eye.abs().max_element())
        .max(MIN_SCALE) as f64;
    scale * GEOMETRY_TOLERANCE
}

/// The view frustum `V` between the pushed `near` and `far` planes, slightly widened.
fn view_frustum(frame: &Frame, (near, far): (f64, f64)) -> Body {
    let cam = frame.camera;
    let (right, up, fwd) = cam.basis();
    let (right, up, fwd) = (right.as_dvec3(), up.as_dvec3(), fwd.as_dvec3());
    let eye = cam.eye.as_dvec3();
    // Half-extents at unit depth (perspective: the frustum's sides spread with depth) or
    // in world units (orthographic: a box).
    let (tw, th, spread) = match cam.projection {
        Projection::Perspective => {
            let th = ((cam.fov_y_deg as f64).to_radians() * 0.5).tan() * (1.0 + TANGENT_WIDENING);
            (th * cam.aspect() as f64, th, true)
        }
        Projection::Orthographic { xmag, ymag } => {
            let widen = 1.0 + TANGENT_WIDENING;
            (xmag as f64 * widen, ymag as f64 * widen, false)
        }
    };
    Body::hexahedron(std::array::from_fn(|i| {
        let d = if i & 4 != 0 { far } else { near };
        let x = if i & 1 != 0 { tw } else { -tw };
        let y = if i & 2 != 0 { th } else { -th };
        let s = if spread { d } else { 1.0 };
        eye + fwd * d + right * (x * s) + up * (y * s)
    }))
}

/// The vertices of the body `H = hull(B ∪ l) ∩ S` of this frame, whose receivers `rec` span
/// the view depths `near..far`; `tol` is [`geometry_tolerance`].
pub(super) fn shadow_body(
    frame: &Frame,
    rec: &Receivers,
    near_far: (f64, f64),
    tol: f64,
) -> Vec<DVec3> {
    let scene = &frame.scene.bounds;
    // B: the part of the view frustum that holds the lit receivers.
    let diag = scene.diagonal() as f64;
    let rpad = diag * RECEIVER_PAD + tol;
    let mut b = view_frustum(frame, near_far).clip_all(&box_planes(&rec.bounds, rpad), tol);
    let light_point = match *frame.light {
        Light::Directional { to_light } => LightPoint::Towards(to_light.as_dvec3().normalize()),
        Light::Point { position } => LightPoint::At(position.as_dvec3()),
        Light::Spot {
            position,
            target,
            fov_deg,
        } => {
            b = b.clip_all(&spot_planes(position, target, fov_deg), tol);
            LightPoint::At(position.as_dvec3())
        }
    };
    if b.is_empty() {
        // Rounding removed a body that holds receivers: fall back to their box.
        b = Body::from_box(&rec.bounds, rpad);
    }
    // H = hull(B ∪ l) ∩ S.
    let sbox = Body::from_box(scene, rpad);
    let mut hbody = sbox.clip_all(&hull_planes(&b, light_point, tol), tol);
    if hbody.is_empty() {
        hbody = b.clone();
    }
    hbody.vertices(tol)
}
