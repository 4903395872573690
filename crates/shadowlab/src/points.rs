//! Visibility of arbitrary points with normals, not tied to an image: the shadow term
//! towards a light of each point, by any technique that can serve it.
//!
//! The points are laid out as the covered samples of a near-square [`ViewSamples`] (row
//! after row, the last row padded with uncovered samples) and handed to the technique as a
//! frame, so every technique runs its own unchanged code on them:
//! - `raytrace` (with `spp=1`) and `afsm` answer exactly: one shadow ray per point, the
//!   point's own triangle skipped;
//! - `sm`, `pcf`, `vsm` and `csm` project the points into their maps. Points have no
//!   screen-space derivatives, so the filtered ones filter at their finest level.
//!
//! `psm`, `asm` and `subpixel` are driven by a camera's pixels (the post-perspective space
//! of the view, the projected eye-pixel areas, the pixel footprints) and refuse point
//! queries; hand them a frame through [`ViewSamples::from_gbuffer`] instead.
//!
//! A point's normal says which side of its surface is asked about: a point whose normal
//! faces away from the light is unlit (0), as a back-facing pixel is. A point given without
//! its triangle skips no triangle, so it must not lie on a caster unless its error bound
//! covers its distance from that caster's plane.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::gbuffer::{derived_error, facing_unit_normal};
use crate::light::Light;
use crate::math::{gamma, vec3, Aabb, Vec3};
use crate::raster::NO_TRIANGLE;
use crate::scene::Scene;
use crate::techniques::{Frame, ShadowTechnique};
use crate::view::ViewSamples;

/// The triangle id of a point that lies on no known triangle: it matches none, so no
/// triangle is skipped for it.
pub const FREE_POINT: u32 = NO_TRIANGLE - 1;

/// Techniques that answer point queries, in [`crate::techniques::ALL`] order.
pub const POINT_TECHNIQUES: &[&str] = &["raytrace", "sm", "pcf", "afsm", "csm", "vsm"];

/// The error bound of a free point's position, in units of γ of its magnitude: the few
/// ulps a caller's f32 point carries. See [`crate::gbuffer::CALLER_POSITION_ULPS`] for
/// the trade-off.
pub const FREE_POINT_ULPS: i32 = 16;

/// The most points one query may hold (the camera pass's pixel limit).
pub const MAX_POINTS: usize = crate::camera::MAX_PIXELS as usize;

/// Points with normals, and optionally the triangle each lies on and its error bound.
#[derive(Clone, Copy, Debug)]
pub struct Points<'a> {
    /// World positions.
    pub position: &'a [Vec3],
    /// Normal of the side asked about at each point (normalized when not of unit length).
    pub normal: &'a [Vec3],
    /// The triangle each point lies on (skipped by its shadow ray), or [`FREE_POINT`];
    /// `None`: every point is free.
    pub triangle: Option<&'a [u32]>,
    /// Per-axis error bound of each position; `None`: derived (see [`FREE_POINT_ULPS`],
    /// and for a point on a triangle the camera pass's bound of that triangle).
    pub position_error: Option<&'a [Vec3]>,
}

impl<'a> Points<'a> {
    /// Free points with normals.
    pub fn new(position: &'a [Vec3], normal: &'a [Vec3]) -> Self {
        Points {
            position,
            normal,
            triangle: None,
            position_error: None,
        }
    }
}

/// The points as the covered samples of a near-square view (see the module doc), with a
/// camera that frames them; fails naming the first bad point.
pub fn points_view(scene: &Scene, points: &Points) -> Result<ViewSamples> {
    let n = points.position.len();
    let lens = [
        ("normals", Some(points.normal.len())),
        ("triangles", points.triangle.map(<[u32]>::len)),
        ("error bounds", points.position_error.map(<[Vec3]>::len)),
    ];
    for (what, len) in lens {
        if let Some(len) = len.filter(|&l| l != n) {
            return Err(Error::param(format!(
                "{len} {what} given for {n} points; give one per point"
            )));
        }
    }
    if n == 0 || n > MAX_POINTS {
        return Err(Error::param(format!(
            "a point query needs 1..={MAX_POINTS} points, not {n}"
        )));
    }
    let width = (n as f64).sqrt().ceil() as u32;
    let height = (n as u32).div_ceil(width);
    let bounds = Aabb::from_points(points.position.iter().filter(|p| p.is_finite()));
    let centre = if bounds.is_empty() {
        Vec3::ZERO
    } else {
        bounds.center()
    };
    let reach = scene.bounds.union(&bounds).diagonal().max(1.0);
    let mut camera = Camera::look_at(centre + vec3(0.0, 0.0, reach), centre, 45.0, width, height);
    camera.fit_depth_range(&scene.bounds.union(&bounds));
    let total = (width * height) as usize;
    let mut vs = ViewSamples {
        width,
        height,
        triangle: vec![NO_TRIANGLE; total],
        position: vec![Vec3::ZERO; total],
        position_error: vec![Vec3::ZERO; total],
        normal: vec![Vec3::ZERO; total],
        depth: vec![f32::INFINITY; total],
        dpdx: vec![Vec3::ZERO; total],
        dpdy: vec![Vec3::ZERO; total],
        camera,
        time_ms: 0.0,
    };
    for k in 0..n {
        let p = points.position[k];
        if !p.is_finite() {
            return Err(Error::param(format!("point {k}: position is not finite")));
        }
        // A zero "ray" keeps the normal's direction: points have no viewer to face.
        vs.normal[k] = facing_unit_normal(points.normal[k], Vec3::ZERO)
            .ok_or_else(|| Error::param(format!("point {k}: normal is zero or not finite")))?;
        let t = points.triangle.map_or(FREE_POINT, |t| t[k]);
        if t != FREE_POINT && t as usize >= scene.len() {
            return Err(Error::param(format!(
                "point {k}: triangle {t} is not in scene {} ({} triangles)",
                scene.name,
                scene.len()
            )));
        }
        vs.triangle[k] = t;
        vs.position[k] = p;
        vs.depth[k] = (p - camera.eye).dot(camera.forward());
        vs.position_error[k] = match (points.position_error, t) {
            (Some(e), _) => e[k],
            (None, FREE_POINT) => p.abs() * gamma(FREE_POINT_ULPS),
            (None, t) => derived_error(scene.triangle(t as usize), p),
        };
    }
    Ok(vs)
}

/// The shadow term towards `light` of every point, by `technique` (one of
/// [`POINT_TECHNIQUES`]): RGB transmittance, 1 = lit.
///
/// ```
/// use shadowlab::prelude::*;
/// use shadowlab::points::{visibility_of_points, Points};
/// let scene = shadowlab::scene::load("chessboard", &Default::default()).unwrap();
/// let light = scene.light.unwrap();
/// // Two points looking up: one high above the board, one at the scene's centre.
/// let position = [vec3(0.0, 50.0, 0.0), scene.bounds.center()];
/// let normal = [Vec3::Y, Vec3::Y];
/// let mut afsm = shadowlab::techniques::create("afsm").unwrap();
/// let vis = visibility_of_points(afsm.as_mut(), &scene, &light, &Points::new(&position, &normal))
///     .unwrap();
/// assert_eq!(vis.len(), 2);
/// ```
pub fn visibility_of_points(
    technique: &mut dyn ShadowTechnique,
    scene: &Scene,
    light: &Light,
    points: &Points,
) -> Result<Vec<Vec3>> {
    let name = technique.name();
    if !POINT_TECHNIQUES.contains(&name) {
        return Err(Error::param(format!(
            "technique {name} cannot answer point queries (it needs a camera's pixels); use one of {}, or hand it a frame with ViewSamples::from_gbuffer",
            POINT_TECHNIQUES.join(", ")
        )));
    }
    if let Some(spp) = technique.params().get("spp").filter(|s| **s != 1) {
        return Err(Error::param(format!(
            "technique {name} with spp={spp} cannot answer point queries (supersampling needs a camera's pixels); use spp=1"
        )));
    }
    light.validate()?;
    let light = light.normalized();
    let view = points_view(scene, points)?;
    let frame = Frame::new(scene, &view.camera, &light, &view);
    let shadows = technique.render(&frame)?;
    let mut v = shadows.visibility.value;
    v.truncate(points.position.len());
    Ok(v)
}
