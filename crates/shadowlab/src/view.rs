//! The camera pass: the shared rasterizer fills a G-buffer of view samples once per
//! frame, and every technique reads it instead of rasterizing the view again.
//!
//! Each covered pixel stores the triangle seen through its centre, the world position
//! where the primary ray meets that triangle's plane (exact for the centre ray, with a
//! floating-point error bound for offsetting shadow rays), the face normal turned towards
//! the camera, the view depth, and the screen-space derivatives of the world position —
//! the differences to where the rays through the neighbouring pixel centres meet the
//! same plane, the software equivalent of the GPU's `ddx`/`ddy`.

use crate::camera::Camera;
use crate::math::{intersect_plane, SurfacePoint, Vec3};
use crate::raster::{self, NO_TRIANGLE};
use crate::scene::Scene;
use rayon::prelude::*;

/// Per-pixel surface samples of one camera pass.
#[derive(Clone, Debug)]
pub struct ViewSamples {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Triangle seen at each pixel, or [`NO_TRIANGLE`].
    pub triangle: Vec<u32>,
    /// World position of each covered pixel.
    pub position: Vec<Vec3>,
    /// Per-axis floating-point error bound of `position`.
    pub position_error: Vec<Vec3>,
    /// Unit face normal, turned to face the camera.
    pub normal: Vec<Vec3>,
    /// View depth (distance along the view axis).
    pub depth: Vec<f32>,
    /// World-position change per pixel step in x (0 where undefined).
    pub dpdx: Vec<Vec3>,
    /// World-position change per pixel step in y (0 where undefined).
    pub dpdy: Vec<Vec3>,
    /// The camera the samples were taken with.
    pub camera: Camera,
    /// Wall time of the pass in milliseconds.
    pub time_ms: f64,
}

impl ViewSamples {
    /// Runs the camera pass.
    pub fn render(scene: &Scene, camera: &Camera) -> Self {
        let t0 = std::time::Instant::now();
        let (w, h) = (camera.width, camera.height);
        let clip_from_world = camera.clip_from_world();
        let setups = raster::setup(scene.len(), w, h, |i| {
            let c = scene.triangle(i).map(|p| clip_from_world * p.extend(1.0));
            // The depth test runs on view depth, which is clip w.
            (c, c.map(|c| c.w))
        });
        let buf = raster::depth_buffer(&setups, w, h);
        let n = (w * h) as usize;
        let mut vs = ViewSamples {
            width: w,
            height: h,
            triangle: buf.id,
            position: vec![Vec3::ZERO; n],
            position_error: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            dpdx: vec![Vec3::ZERO; n],
            dpdy: vec![Vec3::ZERO; n],
            camera: *camera,
            time_ms: 0.0,
        };
        let eye = camera.eye;
        let fwd = camera.forward();
        let rays = camera.rays();
        let triangle = &vs.triangle;
        let rows: Vec<_> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut row = Vec::with_capacity(w as usize);
                for x in 0..w {
                    let id = triangle[(y * w + x) as usize];
                    if id == NO_TRIANGLE {
                        row.push(None);
                        continue;
                    }
                    let v = scene.triangle(id as usize);
                    let cx = x as f32 + 0.5;
                    let cy = y as f32 + 0.5;
                    let d = rays.direction(cx, cy);
                    let Some(hit) = intersect_plane(eye, d, v) else {
                        row.push(None);
                        continue;
                    };
                    let sp = SurfacePoint::from_barycentrics(v, hit.b);
                    let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                    if n.dot(d) > 0.0 {
                        n = -n;
                    }
                    // Neighbouring centre rays meet the same plane at t = n·(p − eye) / n·dir.
                    let plane = n.dot(sp.p - eye);
                    let at = |dx: f32, dy: f32| {
                        let dir = rays.direction(cx + dx, cy + dy);
                        let t = plane / n.dot(dir);
                        if t > 0.0 && t.is_finite() {
                            eye + dir * t - sp.p
                        } else {
                            Vec3::ZERO
                        }
                    };
                    row.push(Some((
                        sp,
                        n,
                        (sp.p - eye).dot(fwd),
                        at(1.0, 0.0),
                        at(0.0, 1.0),
                    )));
                }
                row
            })
            .collect();
        for (y, row) in rows.into_iter().enumerate() {
            for (x, s) in row.into_iter().enumerate() {
                let k = y * w as usize + x;
                match s {
                    Some((sp, n, depth, dx, dy)) if sp.p.is_finite() && n != Vec3::ZERO => {
                        vs.position[k] = sp.p;
                        vs.position_error[k] = sp.error;
                        vs.normal[k] = n;
                        vs.depth[k] = depth;
                        vs.dpdx[k] = dx;
                        vs.dpdy[k] = dy;
                    }
                    _ => vs.triangle[k] = NO_TRIANGLE,
                }
            }
        }
        vs.time_ms = t0.elapsed().as_secs_f64() * 1e3;
        vs
    }

    /// True when pixel `k` shows a surface.
    #[inline]
    pub fn covered(&self, k: usize) -> bool {
        self.triangle[k] != NO_TRIANGLE
    }

    /// Number of covered pixels.
    pub fn covered_count(&self) -> usize {
        self.triangle.iter().filter(|&&t| t != NO_TRIANGLE).count()
    }

    /// The surface point of pixel `k` with its error bound.
    #[inline]
    pub fn surface_point(&self, k: usize) -> SurfacePoint {
        SurfacePoint {
            p: self.position[k],
            error: self.position_error[k],
        }
    }

    /// Bounds of the covered positions (the visible receivers).
    pub fn receiver_bounds(&self) -> crate::math::Aabb {
        let mut b = crate::math::Aabb::EMPTY;
        for k in 0..self.triangle.len() {
            if self.covered(k) {
                b.grow(self.position[k]);
            }
        }
        b
    }
}
