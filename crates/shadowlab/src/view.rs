//! The camera pass: the shared rasterizer fills a G-buffer of view samples once per
//! frame, and every technique reads it instead of rasterizing the view again.
//!
//! Each covered pixel stores the triangle seen through its centre, the world position
//! where the primary ray meets that triangle's plane (exact for the centre ray, with a
//! floating-point error bound for offsetting shadow rays), the face normal turned towards
//! the camera, the view depth, and the screen-space derivatives of the world position —
//! the differences to where the rays through the neighbouring pixel centres meet the
//! same plane, the software equivalent of the GPU's `ddx`/`ddy`.

use crate::camera::{Camera, RayGenerator};
use crate::error::{Error, Result};
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

/// `v` resized to `n` elements: kept as it is when it has that length already (its
/// contents are overwritten by the caller), else refilled with `fill`.
fn fit<T: Clone>(v: &mut Vec<T>, n: usize, fill: T, what: &str) -> Result<()> {
    if v.len() != n {
        *v = Vec::new();
        *v = crate::limits::try_filled(n, fill, what)?;
    }
    Ok(())
}

/// The surface of triangle `id` seen through the centre of pixel `(x, y)`.
struct Sample {
    point: SurfacePoint,
    normal: Vec3,
    depth: f32,
    dpdx: Vec3,
    dpdy: Vec3,
}

/// Where the primary ray through the centre of pixel `(x, y)` meets the plane of triangle
/// `id`, with the face normal turned to the camera and the derivatives; `None` when the ray
/// runs along the plane or the result is not finite.
fn sample(
    scene: &Scene,
    rays: &RayGenerator,
    eye: Vec3,
    fwd: Vec3,
    id: u32,
    x: u32,
    y: u32,
) -> Option<Sample> {
    let v = scene.triangle(id as usize);
    let cx = x as f32 + 0.5;
    let cy = y as f32 + 0.5;
    let (o, d) = rays.ray(cx, cy);
    let hit = intersect_plane(o, d, v)?;
    let sp = SurfacePoint::from_barycentrics(v, hit.b);
    let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    if n.dot(d) > 0.0 {
        n = -n;
    }
    if !sp.p.is_finite() || n == Vec3::ZERO {
        return None;
    }
    let at = |dx: f32, dy: f32| neighbour_offset(rays, n, sp.p, cx + dx, cy + dy);
    Some(Sample {
        point: sp,
        normal: n,
        depth: (sp.p - eye).dot(fwd),
        dpdx: at(1.0, 0.0),
        dpdy: at(0.0, 1.0),
    })
}

/// Where the primary ray through image position `(x, y)` meets the plane through `p` of
/// normal `n`, relative to `p`: t = n·(p − origin) / n·dir, as the camera pass computes a
/// neighbouring pixel's derivative; zero where the ray does not meet the plane ahead.
pub(crate) fn neighbour_offset(rays: &RayGenerator, n: Vec3, p: Vec3, x: f32, y: f32) -> Vec3 {
    let (o, dir) = rays.ray(x, y);
    let t = n.dot(p - o) / n.dot(dir);
    if t > 0.0 && t.is_finite() {
        o + dir * t - p
    } else {
        Vec3::ZERO
    }
}

/// The scene's triangles set up for the camera's rasterization, with view depth as the
/// attribute the depth test runs on: clip `w` of a perspective camera, the distance from
/// the eye's plane of an orthographic one (whose clip `w` is 1).
fn camera_setup(scene: &Scene, camera: &Camera) -> Vec<raster::SetupTriangle> {
    let clip_from_world = camera.clip_from_world();
    let ortho = camera.is_orthographic();
    raster::setup(scene.len(), camera.width, camera.height, |i| {
        let v = scene.triangle(i);
        let c = v.map(|p| clip_from_world * p.extend(1.0));
        let depth = if ortho {
            v.map(|p| camera.view_depth(p))
        } else {
            c.map(|c| c.w)
        };
        (c, depth)
    })
}

impl ViewSamples {
    /// Runs the camera pass; panics where the memory for its buffers is not there (see
    /// [`ViewSamples::try_render`]).
    pub fn render(scene: &Scene, camera: &Camera) -> Self {
        Self::try_render(scene, camera).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Runs the camera pass, or fails with a sentence when its per-pixel buffers cannot
    /// be allocated.
    pub fn try_render(scene: &Scene, camera: &Camera) -> crate::error::Result<Self> {
        let mut vs = Self::unsampled(camera);
        vs.render_into(scene, camera)?;
        Ok(vs)
    }

    /// The image size and camera of `camera` with no per-pixel data: what a frame holds
    /// when its camera pass stayed elsewhere (on the GPU), for a technique that reads none
    /// of it.
    pub fn unsampled(camera: &Camera) -> Self {
        ViewSamples {
            width: camera.width,
            height: camera.height,
            triangle: Vec::new(),
            position: Vec::new(),
            position_error: Vec::new(),
            normal: Vec::new(),
            depth: Vec::new(),
            dpdx: Vec::new(),
            dpdy: Vec::new(),
            camera: *camera,
            time_ms: 0.0,
        }
    }

    /// Runs the camera pass into these samples' buffers, kept from an earlier frame: a
    /// sequence or an interactive view that owns one `ViewSamples` reuses memory that is
    /// already mapped instead of page-faulting tens of megabytes in every frame, and every
    /// per-pixel array is written once a frame (buffers of another size are reallocated).
    /// The result equals [`ViewSamples::try_render`]'s bit for bit. Fails with a sentence
    /// when the buffers cannot be allocated.
    pub fn render_into(&mut self, scene: &Scene, camera: &Camera) -> crate::error::Result<()> {
        let t0 = std::time::Instant::now();
        let (w, h) = (camera.width, camera.height);
        let n = w as usize * h as usize;
        let what = format!("the {w}x{h} camera pass");
        fit(&mut self.triangle, n, NO_TRIANGLE, &what)?;
        for v in [
            &mut self.position,
            &mut self.position_error,
            &mut self.normal,
            &mut self.dpdx,
            &mut self.dpdy,
        ] {
            fit(v, n, Vec3::ZERO, &what)?;
        }
        fit(&mut self.depth, n, f32::INFINITY, &what)?;
        (self.width, self.height, self.camera) = (w, h, *camera);
        let setups = camera_setup(scene, camera);
        // An alpha-masked surface is no surface where its texture cuts it out.
        let masked = scene.has_alpha_masks();
        raster::nearest_ids_where(&setups, w, h, &mut self.triangle, |f| {
            !masked || !scene.cut_out(f.id as usize, f.bary())
        });
        let eye = camera.eye;
        let fwd = camera.forward();
        let rays = camera.rays();
        let wu = w as usize;
        if wu > 0 {
            // Each row written in place by one task, every pixel once: no per-row
            // intermediate, no serial copy, no clearing pass.
            self.triangle
                .par_chunks_mut(wu)
                .zip(self.position.par_chunks_mut(wu))
                .zip(self.position_error.par_chunks_mut(wu))
                .zip(self.normal.par_chunks_mut(wu))
                .zip(self.depth.par_chunks_mut(wu))
                .zip(self.dpdx.par_chunks_mut(wu))
                .zip(self.dpdy.par_chunks_mut(wu))
                .enumerate()
                .for_each(
                    |(y, ((((((triangle, position), error), normal), depth), dpdx), dpdy))| {
                        for x in 0..wu {
                            let id = triangle[x];
                            let s = if id == NO_TRIANGLE {
                                None
                            } else {
                                sample(scene, &rays, eye, fwd, id, x as u32, y as u32)
                            };
                            match s {
                                Some(s) => {
                                    position[x] = s.point.p;
                                    error[x] = s.point.error;
                                    normal[x] = s.normal;
                                    depth[x] = s.depth;
                                    dpdx[x] = s.dpdx;
                                    dpdy[x] = s.dpdy;
                                }
                                None => {
                                    triangle[x] = NO_TRIANGLE;
                                    position[x] = Vec3::ZERO;
                                    error[x] = Vec3::ZERO;
                                    normal[x] = Vec3::ZERO;
                                    depth[x] = f32::INFINITY;
                                    dpdx[x] = Vec3::ZERO;
                                    dpdy[x] = Vec3::ZERO;
                                }
                            }
                        }
                    },
                );
        }
        self.time_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// The samples of a camera pass run elsewhere (the GPU's): `camera` and, row-major
    /// from the top row, each pixel's triangle (or [`NO_TRIANGLE`]), position, its error
    /// bound and the face normal turned to the camera, as [`ViewSamples::render_into`]
    /// forms them. The view depth and the derivatives are formed here from those, as the
    /// library's pass forms them. `None` when the arrays do not hold one entry a pixel.
    pub fn from_samples(
        camera: &Camera,
        triangle: Vec<u32>,
        position: Vec<Vec3>,
        position_error: Vec<Vec3>,
        normal: Vec<Vec3>,
    ) -> Option<Self> {
        let n = camera.width as usize * camera.height as usize;
        if [
            triangle.len(),
            position.len(),
            position_error.len(),
            normal.len(),
        ]
        .iter()
        .any(|&l| l != n)
        {
            return None;
        }
        let (eye, fwd, rays) = (camera.eye, camera.forward(), camera.rays());
        let w = camera.width.max(1) as usize;
        let per_pixel = |k: usize| {
            if triangle[k] == NO_TRIANGLE {
                return (f32::INFINITY, Vec3::ZERO, Vec3::ZERO);
            }
            let (p, nk) = (position[k], normal[k]);
            let (cx, cy) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            (
                (p - eye).dot(fwd),
                neighbour_offset(&rays, nk, p, cx + 1.0, cy),
                neighbour_offset(&rays, nk, p, cx, cy + 1.0),
            )
        };
        let derived: Vec<(f32, Vec3, Vec3)> = (0..n).into_par_iter().map(per_pixel).collect();
        Some(ViewSamples {
            width: camera.width,
            height: camera.height,
            triangle,
            position,
            position_error,
            normal,
            depth: derived.iter().map(|d| d.0).collect(),
            dpdx: derived.iter().map(|d| d.1).collect(),
            dpdy: derived.iter().map(|d| d.2).collect(),
            camera: *camera,
            time_ms: 0.0,
        })
    }

    /// Bytes of the per-pixel arrays the camera pass writes.
    pub fn bytes_per_pixel() -> usize {
        2 * std::mem::size_of::<u32>() + 5 * std::mem::size_of::<Vec3>()
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

/// The most layer samples one frame may hold (see [`ViewLayers::render`]): 2²⁶, about 3 GiB
/// of samples.
pub const MAX_LAYER_SAMPLES: usize = 1 << 26;

/// The surfaces behind semi-transparent ones: for every pixel whose nearest surface lets
/// light through, each further surface the pixel's centre ray meets, front to back, down to
/// and including the first opaque one (all of them when none is opaque). The nearest
/// surface itself is the pixel's [`ViewSamples`] entry; these are the other layers a
/// renderer composites behind it, each a receiver with its own shadow term.
///
/// Layer samples are stored pixel by pixel (pixel `k`'s are `offsets[k]..offsets[k + 1]`),
/// each computed exactly as the camera pass computes its samples: where the centre ray
/// meets the triangle's plane, with the error bound, and the face normal turned to the
/// camera.
#[derive(Clone, Debug, Default)]
pub struct ViewLayers {
    /// Start of each pixel's layer samples, and the total at the end (`pixels + 1` entries).
    pub offsets: Vec<u32>,
    /// The pixel each layer sample belongs to.
    pub pixel: Vec<u32>,
    /// Triangle of each layer sample.
    pub triangle: Vec<u32>,
    /// World position of each layer sample.
    pub position: Vec<Vec3>,
    /// Per-axis floating-point error bound of `position`.
    pub position_error: Vec<Vec3>,
    /// Unit face normal, turned to face the camera.
    pub normal: Vec<Vec3>,
    /// View depth (distance along the view axis).
    pub depth: Vec<f32>,
    /// Wall time of the pass in milliseconds.
    pub time_ms: f64,
}

impl ViewLayers {
    /// Collects the layers behind the semi-transparent nearest surfaces of `view` (empty
    /// when the scene is opaque). The rasterizer gathers every fragment of the pixels that
    /// see such a surface (an A-buffer per tile); fragments are ordered by depth, ties by
    /// triangle index, the order of the camera pass's own depth test, whose winner comes
    /// first and is skipped.
    pub fn render(scene: &Scene, camera: &Camera, view: &ViewSamples) -> Result<Self> {
        let t0 = std::time::Instant::now();
        let (w, h) = (camera.width, camera.height);
        let n = (w * h) as usize;
        let mut out = ViewLayers {
            offsets: vec![0; n + 1],
            ..Default::default()
        };
        if !scene.has_transparency() {
            out.time_ms = t0.elapsed().as_secs_f64() * 1e3;
            return Ok(out);
        }
        let setups = camera_setup(scene, camera);
        let see_through =
            |k: usize| view.covered(k) && !scene.material_of(view.triangle[k] as usize).is_opaque();
        // Every fragment of a pixel whose nearest surface is see-through, that surface's own
        // included: (pixel, depth, triangle).
        let tiles = raster::rasterize(
            &setups,
            w,
            h,
            |_| Vec::new(),
            |frags: &mut Vec<(u32, f32, u32)>, _, f| {
                let k = (f.y * w + f.x) as usize;
                if see_through(k) && !scene.cut_out(f.id as usize, f.bary()) {
                    frags.push((k as u32, f.depth, f.id));
                }
            },
        );
        let total: usize = tiles.iter().map(|(_, f)| f.len()).sum();
        if total > MAX_LAYER_SAMPLES {
            return Err(Error::Limit(format!(
                "the semi-transparent surfaces of scene {:?} put {total} surfaces under the pixels that see through them, above the limit of {MAX_LAYER_SAMPLES} layer samples; lower the resolution (--width/--height)",
                scene.name
            )));
        }
        let mut frags: Vec<(u32, f32, u32)> = Vec::with_capacity(total);
        for (_, f) in tiles {
            frags.extend(f);
        }
        frags.par_sort_unstable_by(|a, b| {
            a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2))
        });
        // Each pixel's first fragment in (depth, triangle) order is the camera pass's own
        // (its depth test keeps the nearest, ties to the lower index); keep the ones after
        // it down to the first opaque one.
        let mut kept = Vec::with_capacity(frags.len());
        let mut i = 0;
        while i < frags.len() {
            let k = frags[i].0;
            debug_assert_eq!(frags[i].2, view.triangle[k as usize]);
            i += 1;
            while i < frags.len() && frags[i].0 == k {
                kept.push(frags[i]);
                let opaque = scene.material_of(frags[i].2 as usize).is_opaque();
                i += 1;
                if opaque {
                    while i < frags.len() && frags[i].0 == k {
                        i += 1;
                    }
                }
            }
        }
        let eye = camera.eye;
        let fwd = camera.forward();
        let rays = camera.rays();
        let samples: Vec<Option<Sample>> = kept
            .par_iter()
            .with_min_len(1024)
            .map(|&(k, _, id)| sample(scene, &rays, eye, fwd, id, k % w, k / w))
            .collect();
        for (&(k, _, id), s) in kept.iter().zip(samples) {
            let Some(s) = s else { continue };
            out.offsets[k as usize + 1] += 1;
            out.pixel.push(k);
            out.triangle.push(id);
            out.position.push(s.point.p);
            out.position_error.push(s.point.error);
            out.normal.push(s.normal);
            out.depth.push(s.depth);
        }
        for k in 0..n {
            out.offsets[k + 1] += out.offsets[k];
        }
        out.time_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(out)
    }

    /// Number of layer samples.
    pub fn len(&self) -> usize {
        self.triangle.len()
    }

    /// True when no pixel has a layer behind its nearest surface.
    pub fn is_empty(&self) -> bool {
        self.triangle.is_empty()
    }

    /// The layer samples of pixel `k`, front to back.
    #[inline]
    pub fn of_pixel(&self, k: usize) -> std::ops::Range<usize> {
        self.offsets[k] as usize..self.offsets[k + 1] as usize
    }

    /// The surface point of layer sample `i` with its error bound.
    #[inline]
    pub fn surface_point(&self, i: usize) -> SurfacePoint {
        SurfacePoint {
            p: self.position[i],
            error: self.position_error[i],
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.offsets.len() * 4 + self.len() * (4 + 4 + 12 + 12 + 12 + 4)
    }
}
