//! A renderer's own G-buffer as the camera pass: [`ViewSamples::from_gbuffer`] turns the
//! per-pixel positions, normals and coverage of a frame that some other renderer drew into
//! the [`ViewSamples`] every technique reads, so shadowlab shades *that* frame instead of
//! rasterizing the view itself.
//!
//! What is optional and how it is derived when absent:
//! - **Triangle ids** (the reference and `afsm` skip a sample's own triangle; `asm`'s id
//!   test and `subpixel`'s facets need it; shading reads its material): the closest
//!   triangle along the primary ray that reaches the position, traced on the scene's BVH.
//! - **Screen-space derivatives** (`asm` sizes its tiles and `pcf`, `vsm` and `csm` their
//!   filter footprints by them): where the primary rays through the neighbouring pixel
//!   centres meet the plane through the position with the pixel's normal — the camera
//!   pass's own formula, so a planar G-buffer gets the camera pass's derivatives bit for bit.
//! - **Position error bounds** (how far shadow rays leave the surface): the camera pass's
//!   bound for a point inside the pixel's triangle, `(γ(7) + γ(16))·max|vᵢ|`, plus
//!   [`CALLER_POSITION_ULPS`] ulps of the position itself for the caller's own rounding.
//!
//! The normal must be the geometric (face) normal: the back-facing test of
//! [`crate::light::Light::illuminates`] and the shadow-ray offset read it, and a shading
//! normal makes both disagree with the geometry near silhouettes. Normals are turned to
//! face the camera, as the camera pass's are, and normalized only when they are not of
//! unit length already (so unit inputs are kept bit for bit).

use crate::camera::{Camera, RayGenerator};
use crate::error::{Error, Result};
use crate::math::{gamma, Vec3};
use crate::raster::NO_TRIANGLE;
use crate::reference::Reference;
use crate::scene::Scene;
use crate::view::{neighbour_offset, ViewSamples};

/// A normal whose squared length is within this of 1 counts as unit length and is kept bit
/// for bit; others are normalized. Loose enough for normals stored at half precision,
/// tight enough that a kept normal's length error stays far below the offset bounds.
pub const NORMAL_UNIT_TOLERANCE: f32 = 1e-3;

/// The rounding a caller's positions are assumed to carry beyond the camera pass's own
/// bound, in units of γ (about one ulp each): positions interpolated or reconstructed in
/// f32 are a few ulps off their plane. Larger values push shadow rays further off the
/// surface (light leaks into contact shadows); smaller ones let rays re-hit it (acne).
pub const CALLER_POSITION_ULPS: i32 = 8;

/// A caller's G-buffer: `width × height` pixels, row-major from the top row, pixel
/// `(x, y)` at index `y·width + x`, covering `[x, x+1) × [y, y+1)` with its primary ray
/// through the centre `(x + 0.5, y + 0.5)` (the camera's conventions).
#[derive(Clone, Copy, Debug)]
pub struct GBuffer<'a> {
    /// Image width; must equal the camera's.
    pub width: u32,
    /// Image height; must equal the camera's.
    pub height: u32,
    /// World position seen through each pixel centre (read where covered).
    pub position: &'a [Vec3],
    /// Geometric normal of the surface seen at each pixel (read where covered).
    pub normal: &'a [Vec3],
    /// True where a surface covers the pixel centre.
    pub coverage: &'a [bool],
    /// The scene triangle seen at each covered pixel; derived when `None`.
    pub triangle: Option<&'a [u32]>,
    /// World-position change per pixel step in x; derived when `None`.
    pub dpdx: Option<&'a [Vec3]>,
    /// World-position change per pixel step in y; derived when `None`.
    pub dpdy: Option<&'a [Vec3]>,
    /// Per-axis error bound of each position; derived when `None`.
    pub position_error: Option<&'a [Vec3]>,
}

impl<'a> GBuffer<'a> {
    /// A G-buffer of positions, normals and coverage only; everything else is derived.
    pub fn new(
        width: u32,
        height: u32,
        position: &'a [Vec3],
        normal: &'a [Vec3],
        coverage: &'a [bool],
    ) -> Self {
        GBuffer {
            width,
            height,
            position,
            normal,
            coverage,
            triangle: None,
            dpdx: None,
            dpdy: None,
            position_error: None,
        }
    }

    /// The complete G-buffer of a camera pass (ids, derivatives and error bounds
    /// included), as a renderer that keeps them all would hand it over.
    pub fn of_view(view: &'a ViewSamples, coverage: &'a [bool]) -> Self {
        GBuffer {
            width: view.width,
            height: view.height,
            position: &view.position,
            normal: &view.normal,
            coverage,
            triangle: Some(&view.triangle),
            dpdx: Some(&view.dpdx),
            dpdy: Some(&view.dpdy),
            position_error: Some(&view.position_error),
        }
    }

    fn check_lengths(&self) -> Result<usize> {
        let n = self.width as usize * self.height as usize;
        let fields: [(&str, Option<usize>); 7] = [
            ("position", Some(self.position.len())),
            ("normal", Some(self.normal.len())),
            ("coverage", Some(self.coverage.len())),
            ("triangle", self.triangle.map(<[u32]>::len)),
            ("dpdx", self.dpdx.map(<[Vec3]>::len)),
            ("dpdy", self.dpdy.map(<[Vec3]>::len)),
            ("position_error", self.position_error.map(<[Vec3]>::len)),
        ];
        for (name, len) in fields {
            if let Some(len) = len.filter(|&l| l != n) {
                return Err(Error::param(format!(
                    "G-buffer {name} has {len} entries, not width × height = {} × {} = {n}",
                    self.width, self.height
                )));
            }
        }
        Ok(n)
    }
}

/// `n` of unit length turned to face against the ray direction `d`, or `None` when it is
/// zero or not finite.
pub(crate) fn facing_unit_normal(n: Vec3, d: Vec3) -> Option<Vec3> {
    let len2 = n.length_squared();
    if !len2.is_finite() || len2 == 0.0 {
        return None;
    }
    let mut n = if (len2 - 1.0).abs() > NORMAL_UNIT_TOLERANCE {
        n / len2.sqrt()
    } else {
        n
    };
    if n.dot(d) > 0.0 {
        n = -n;
    }
    Some(n)
}

/// The conservative error bound of a point on triangle `v` whose position came from a
/// caller (see the module doc).
pub(crate) fn derived_error(v: [Vec3; 3], p: Vec3) -> Vec3 {
    let vmag = v[0].abs().max(v[1].abs()).max(v[2].abs());
    vmag * (gamma(7) + gamma(16)) + p.abs() * gamma(CALLER_POSITION_ULPS)
}

impl ViewSamples {
    /// The camera pass of a frame another renderer drew: its G-buffer seen through
    /// `camera`, over the triangles of `scene` (see the [module doc](crate::gbuffer) for
    /// what is derived when absent). Fails with a sentence naming the field or pixel at
    /// fault: lengths that are not `width × height`, a size that is not the camera's, a
    /// covered pixel with a non-finite position or a zero normal, a triangle id the scene
    /// lacks, or (ids derived) a covered pixel whose ray meets no triangle.
    ///
    /// ```
    /// use shadowlab::prelude::*;
    /// use shadowlab::gbuffer::GBuffer;
    /// let scene = shadowlab::scene::load("chessboard", &Default::default()).unwrap();
    /// let mut camera = scene.camera.unwrap();
    /// (camera.width, camera.height) = (64, 48);
    /// camera.fit_depth_range(&scene.bounds);
    /// // Stand-in for a renderer's own G-buffer: positions, normals and coverage.
    /// let own = ViewSamples::render(&scene, &camera);
    /// let coverage: Vec<bool> = (0..own.triangle.len()).map(|k| own.covered(k)).collect();
    /// let g = GBuffer::new(64, 48, &own.position, &own.normal, &coverage);
    /// let view = ViewSamples::from_gbuffer(&scene, &camera, &g).unwrap();
    /// let light = scene.light.unwrap();
    /// let frame = Frame::new(&scene, &camera, &light, &view);
    /// let shadows = shadowlab::techniques::create("afsm").unwrap().render(&frame).unwrap();
    /// assert_eq!(shadows.visibility.value.len(), 64 * 48);
    /// ```
    pub fn from_gbuffer(scene: &Scene, camera: &Camera, g: &GBuffer) -> Result<Self> {
        let t0 = std::time::Instant::now();
        camera.validate()?;
        if (g.width, g.height) != (camera.width, camera.height) {
            return Err(Error::param(format!(
                "G-buffer of {} × {} pixels does not match the camera's {} × {}",
                g.width, g.height, camera.width, camera.height
            )));
        }
        let n = g.check_lengths()?;
        let w = g.width as usize;
        let pixel = |k: usize| format!("G-buffer pixel ({}, {})", k % w, k / w);
        let rays = camera.rays();
        let (eye, fwd) = (camera.eye, camera.forward());
        let centre_ray = |k: usize| rays.direction((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
        let mut normal = vec![Vec3::ZERO; n];
        for k in (0..n).filter(|&k| g.coverage[k]) {
            if !g.position[k].is_finite() {
                return Err(Error::param(format!(
                    "{}: position is not finite",
                    pixel(k)
                )));
            }
            normal[k] = facing_unit_normal(g.normal[k], centre_ray(k)).ok_or_else(|| {
                Error::param(format!("{}: normal is zero or not finite", pixel(k)))
            })?;
        }
        let triangle = match g.triangle {
            Some(ids) => {
                let mut t = vec![NO_TRIANGLE; n];
                for k in (0..n).filter(|&k| g.coverage[k]) {
                    if ids[k] as usize >= scene.len() {
                        return Err(Error::param(format!(
                            "{}: triangle {} is not in scene {} ({} triangles)",
                            pixel(k),
                            ids[k],
                            scene.name,
                            scene.len()
                        )));
                    }
                    t[k] = ids[k];
                }
                t
            }
            None => derive_triangles(scene, &rays, g, &pixel)?,
        };
        let mut vs = ViewSamples {
            width: g.width,
            height: g.height,
            triangle,
            position: vec![Vec3::ZERO; n],
            position_error: vec![Vec3::ZERO; n],
            normal,
            depth: vec![f32::INFINITY; n],
            dpdx: vec![Vec3::ZERO; n],
            dpdy: vec![Vec3::ZERO; n],
            camera: *camera,
            time_ms: 0.0,
        };
        for k in (0..n).filter(|&k| g.coverage[k]) {
            let p = g.position[k];
            let nk = vs.normal[k];
            vs.position[k] = p;
            vs.depth[k] = (p - eye).dot(fwd);
            vs.position_error[k] = match g.position_error {
                Some(e) => e[k],
                None => derived_error(scene.triangle(vs.triangle[k] as usize), p),
            };
            // Neighbouring centre rays meet the plane through p exactly as the camera pass
            // computes them.
            let (cx, cy) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            let at = |dx: f32, dy: f32| neighbour_offset(&rays, nk, p, cx + dx, cy + dy);
            vs.dpdx[k] = g.dpdx.map_or_else(|| at(1.0, 0.0), |d| d[k]);
            vs.dpdy[k] = g.dpdy.map_or_else(|| at(0.0, 1.0), |d| d[k]);
        }
        vs.time_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(vs)
    }
}

/// The triangle seen at each covered pixel: the closest along the primary ray that reaches
/// the pixel's position.
fn derive_triangles(
    scene: &Scene,
    rays: &RayGenerator,
    g: &GBuffer,
    pixel: &dyn Fn(usize) -> String,
) -> Result<Vec<u32>> {
    use rayon::prelude::*;
    let reference = Reference::build(scene);
    let ids: Vec<u32> = (0..g.coverage.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| {
            if !g.coverage[k] {
                return NO_TRIANGLE;
            }
            let (o, d) = rays.ray_to(g.position[k]);
            reference
                .closest_hit(o, d.normalize_or_zero())
                .map_or(NO_TRIANGLE, |h| h.triangle)
        })
        .collect();
    if let Some(k) = (0..ids.len()).find(|&k| g.coverage[k] && ids[k] == NO_TRIANGLE) {
        return Err(Error::param(format!(
            "{} is covered, but the primary ray through its position meets no triangle of scene {}; pass the triangle ids",
            pixel(k),
            scene.name
        )));
    }
    Ok(ids)
}
