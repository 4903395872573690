//! Lights, and the light-space views that map-based techniques rasterize from.
//!
//! A directional light's view is orthographic and fitted to the visible receivers plus
//! every caster between them and the light; a spot light's view is its own frustum; a
//! point light is a cube of six 90° spot frusta.

use crate::error::{Error, Result};
use crate::math::{vec3, Aabb, Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Light {
    /// Parallel light; `to_light` is the unit vector from the scene towards the light.
    Directional {
        /// Unit vector towards the light.
        to_light: Vec3,
    },
    /// A cone of light from `position` towards `target` with full opening angle `fov_deg`.
    Spot {
        /// Light position.
        position: Vec3,
        /// The point the cone's axis passes through.
        target: Vec3,
        /// Full opening angle in degrees.
        fov_deg: f32,
    },
    /// Light in every direction from `position`.
    Point {
        /// Light position.
        position: Vec3,
    },
}

impl Light {
    /// Checks for non-finite values, zero directions and impossible cone angles.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Light::Directional { to_light } => {
                // Only the direction counts: a long vector is scaled, never refused.
                if crate::math::direction(to_light).is_none() {
                    return Err(Error::param(
                        "directional light direction must be a finite, non-zero vector",
                    ));
                }
            }
            Light::Spot {
                position,
                target,
                fov_deg,
            } => {
                if !position.is_finite() || !target.is_finite() {
                    return Err(Error::param(
                        "spot light position and target must be finite",
                    ));
                }
                far_out("spot light position", position)?;
                far_out("spot light target", target)?;
                let len2 = (target - position).length_squared();
                if len2 == 0.0 {
                    return Err(Error::param("spot light target equals its position"));
                }
                if !len2.is_finite() {
                    return Err(Error::param(
                        "spot light target is too far from its position to form a direction",
                    ));
                }
                if !(fov_deg > 0.0 && fov_deg < 179.0) {
                    return Err(Error::param(format!(
                        "spot light cone angle {fov_deg}° is outside (0°, 179°)"
                    )));
                }
            }
            Light::Point { position } => {
                if !position.is_finite() {
                    return Err(Error::param("point light position must be finite"));
                }
                far_out("point light position", position)?;
            }
        }
        Ok(())
    }

    /// The same light with its direction normalized. A direction that is already of unit
    /// length is kept bit for bit, so recorded lights reproduce exactly.
    pub fn normalized(self) -> Light {
        match self {
            Light::Directional { to_light }
                if (to_light.length_squared() - 1.0).abs() > 4.0 * f32::EPSILON =>
            {
                Light::Directional {
                    to_light: crate::math::direction(to_light).unwrap_or(to_light),
                }
            }
            l => l,
        }
    }

    /// The shadow ray from `p`: unit direction towards the light and the distance to it
    /// (infinite for a directional light).
    pub fn shadow_ray(&self, p: Vec3) -> (Vec3, f32) {
        match *self {
            Light::Directional { to_light } => (to_light, f32::INFINITY),
            Light::Spot { position, .. } | Light::Point { position } => {
                let d = position - p;
                let len = d.length();
                (d / len, len)
            }
        }
    }

    /// Whether light can reach `p` on a surface whose unit normal `n` faces the viewer: the
    /// light must be on the viewed side of the surface (otherwise the surface shadows
    /// itself) and, for a spot light, inside its cone. Every technique and the reference
    /// share this test, so they differ only in what they compute for occlusion by *other*
    /// geometry.
    pub fn illuminates(&self, p: Vec3, n: Vec3) -> bool {
        let (l, dist) = self.shadow_ray(p);
        if dist.is_nan() || dist <= 0.0 || n.dot(l) <= 0.0 {
            return false;
        }
        self.cone_contains(l)
    }

    /// Whether the unit direction `l` towards the light (from a scene point) lies inside a
    /// spot light's cone; true for the other kinds.
    pub fn cone_contains(&self, l: Vec3) -> bool {
        match *self {
            Light::Spot {
                position,
                target,
                fov_deg,
            } => {
                let axis = (target - position).normalize();
                let cos_half = (fov_deg.to_radians() * 0.5).cos();
                (-l).dot(axis) >= cos_half
            }
            _ => true,
        }
    }

    /// A short name: `directional`, `spot` or `point`.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Directional { .. } => "directional",
            Light::Spot { .. } => "spot",
            Light::Point { .. } => "point",
        }
    }
}

pub use crate::math::pick_up;

/// The nearest far plane of a perspective light view (world units); the camera module's
/// `CAMERA_MIN_FAR` is the camera's (ten times larger, kept so that images stay as they
/// were).
pub const LIGHT_MIN_FAR: f32 = 1e-4;

/// One square light-space view: what a shadow map is rasterized from.
///
/// The depth stored in maps is *linear*: the distance from the view's eye plane along its
/// axis (`-z` in light view space), for orthographic and perspective views alike, so that
/// biases are in world units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    /// World to light view space (right-handed, looking down −Z).
    pub light_from_world: Mat4,
    /// Light view space to clip space.
    pub clip_from_light: Mat4,
    /// World to clip space.
    pub clip_from_world: Mat4,
    /// True for orthographic views (directional lights).
    pub orthographic: bool,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
    /// Width of the view at unit depth (perspective) or in total (orthographic), world units.
    pub extent: f32,
}

/// Where a world point falls in a light view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Horizontal image coordinate in `[0, 1]` across the view (0 = left).
    pub u: f32,
    /// Vertical image coordinate in `[0, 1]` (0 = top row).
    pub v: f32,
    /// Linear depth from the view's eye plane.
    pub depth: f32,
}

impl LightView {
    /// A view from its world-to-light and light-to-clip transforms, depth range and extent
    /// (see the fields).
    pub fn new(
        light_from_world: Mat4,
        clip_from_light: Mat4,
        ortho: bool,
        near: f32,
        far: f32,
        extent: f32,
    ) -> Self {
        LightView {
            light_from_world,
            clip_from_light,
            clip_from_world: clip_from_light * light_from_world,
            orthographic: ortho,
            near,
            far,
            extent,
        }
    }

    /// Linear depth of `p`.
    #[inline]
    pub fn depth(&self, p: Vec3) -> f32 {
        -self.light_from_world.transform_point3(p).z
    }

    /// Projects `p` into the view. Points behind a perspective eye get non-finite
    /// coordinates; callers treat `u, v` outside `[0, 1]` as outside the view.
    #[inline]
    pub fn project(&self, p: Vec3) -> LightSample {
        let c = self.clip_from_world * p.extend(1.0);
        let inv_w = 1.0 / c.w;
        LightSample {
            u: c.x * inv_w * 0.5 + 0.5,
            v: 0.5 - c.y * inv_w * 0.5,
            depth: self.depth(p),
        }
    }

    /// World size of one texel of an `n`-texel map at linear depth `depth`.
    pub fn texel_size(&self, n: u32, depth: f32) -> f32 {
        if self.orthographic {
            self.extent / n as f32
        } else {
            self.extent * depth.max(self.near) / n as f32
        }
    }

    /// An orthographic view along `-to_light` whose image covers the light-space
    /// rectangle of `receivers` and whose depth range reaches from the nearest point of
    /// `scene` towards the light to the farthest receiver: every caster that can shadow a
    /// receiver lies inside. `pad` widens the rectangle by that fraction on each side.
    pub fn directional(to_light: Vec3, receivers: &Aabb, scene: &Aabb, pad: f32) -> Self {
        let dir = to_light.normalize();
        let c = scene.center();
        let r = scene.diagonal().max(1e-6);
        let eye = c + dir * r;
        let light_from_world = crate::math::look_at_rh(eye, c, pick_up(dir));
        let mut rx = Aabb::EMPTY;
        let src = if receivers.is_empty() {
            scene
        } else {
            receivers
        };
        for p in src.corners() {
            rx.grow(light_from_world.transform_point3(p));
        }
        let mut near = f32::INFINITY;
        for p in scene.corners() {
            near = near.min(-light_from_world.transform_point3(p).z);
        }
        let far_d = -rx.min.z;
        let w = (rx.max.x - rx.min.x).max(rx.max.y - rx.min.y).max(r * 1e-6);
        // A square view keeps texels square; centre the receivers in it.
        let half = w * 0.5 * (1.0 + 2.0 * pad);
        let cx = (rx.min.x + rx.max.x) * 0.5;
        let cy = (rx.min.y + rx.max.y) * 0.5;
        let span = (far_d - near).max(r * 1e-6);
        let near = near - span * 1e-3;
        let far = far_d + span * 1e-3;
        let clip_from_light =
            crate::math::orthographic_rh(cx - half, cx + half, cy - half, cy + half, near, far);
        LightView::new(
            light_from_world,
            clip_from_light,
            true,
            near,
            far,
            2.0 * half,
        )
    }

    /// A perspective view from `position` towards `target` with full angle `fov_deg`,
    /// near and far fitted to `scene`.
    pub fn perspective(position: Vec3, target: Vec3, fov_deg: f32, up: Vec3, scene: &Aabb) -> Self {
        let light_from_world = crate::math::look_at_rh(position, target, up);
        // Geometry closer than `near` would be clipped away; when the light sits inside the
        // scene's box the near plane goes down to a small fraction of far.
        let depths = scene
            .corners()
            .map(|p| -light_from_world.transform_point3(p).z);
        let (near, far) = crate::math::fit_near_far(depths, LIGHT_MIN_FAR);
        let fov = fov_deg.to_radians();
        let clip_from_light = crate::math::perspective_rh(fov, 1.0, near, far);
        LightView::new(
            light_from_world,
            clip_from_light,
            false,
            near,
            far,
            2.0 * (fov * 0.5).tan(),
        )
    }

    /// The six 90° faces of a point light's cube, in the order +X, −X, +Y, −Y, +Z, −Z.
    pub fn cube(position: Vec3, scene: &Aabb) -> [LightView; 6] {
        CUBE_FACES
            .map(|(dir, up)| LightView::perspective(position, position + dir, 90.0, up, scene))
    }
}

/// Axis and up vector of each cube face, in [`LightView::cube`]'s order.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)),
    (vec3(-1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)),
    (vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, -1.0)),
    (vec3(0.0, -1.0, 0.0), vec3(0.0, 0.0, 1.0)),
    (vec3(0.0, 0.0, 1.0), vec3(0.0, 1.0, 0.0)),
    (vec3(0.0, 0.0, -1.0), vec3(0.0, 1.0, 0.0)),
];

/// The cube face that direction `d` (from the light) falls on: its major axis.
#[inline]
pub fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// The light views a map-based technique renders for `light`: one for directional and spot
/// lights, six for a point light. `receivers` is the box of the visible surface points.
pub fn light_views(light: &Light, receivers: &Aabb, scene: &Aabb, pad: f32) -> Vec<LightView> {
    match *light {
        Light::Directional { to_light } => {
            vec![LightView::directional(to_light, receivers, scene, pad)]
        }
        Light::Spot {
            position,
            target,
            fov_deg,
        } => vec![LightView::perspective(
            position,
            target,
            fov_deg,
            pick_up(target - position),
            scene,
        )],
        Light::Point { position } => LightView::cube(position, scene).to_vec(),
    }
}

/// Refuses a point beyond ±[`crate::math::MAX_COORDINATE`], naming it as `what`.
pub(crate) fn far_out(what: &str, p: Vec3) -> Result<()> {
    if crate::math::within_coordinate_limit(p) {
        return Ok(());
    }
    Err(Error::param(format!(
        "{what} ({:e}, {:e}, {:e}) lies beyond ±{:e} on an axis, too far out for distances in single precision; bring it nearer the scene",
        p.x,
        p.y,
        p.z,
        crate::math::MAX_COORDINATE
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_cover_their_directions() {
        let b = Aabb::from_points(&[vec3(-5.0, -5.0, -5.0), vec3(5.0, 5.0, 5.0)]);
        let views = LightView::cube(Vec3::ZERO, &b);
        for d in [
            vec3(1.0, 0.3, -0.2),
            vec3(-0.1, -1.0, 0.9),
            vec3(0.2, 0.1, -1.0),
        ] {
            let f = cube_face(d);
            let s = views[f].project(d * 2.0);
            assert!(
                (0.0..=1.0).contains(&s.u) && (0.0..=1.0).contains(&s.v),
                "{d} -> {f} {s:?}"
            );
        }
    }

    #[test]
    fn directional_view_contains_receivers() {
        let scene = Aabb::from_points(&[vec3(-1.0, 0.0, -1.0), vec3(1.0, 2.0, 1.0)]);
        let rec = Aabb::from_points(&[vec3(-1.0, 0.0, -1.0), vec3(1.0, 0.0, 1.0)]);
        let v = LightView::directional(vec3(0.3, 1.0, 0.2), &rec, &scene, 0.0);
        for p in scene.corners() {
            let s = v.project(p);
            assert!(s.depth >= v.near && s.depth <= v.far);
        }
        for p in rec.corners() {
            let s = v.project(p);
            assert!((-1e-4..=1.0001).contains(&s.u) && (-1e-4..=1.0001).contains(&s.v));
        }
    }
}
