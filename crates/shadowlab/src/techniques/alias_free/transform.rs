//! Stage one of alias-free shadow maps (Aila & Laine 2004, Section 3 "Projection of Sampling
//! Points"; "Transformation of samples" in Table 1): every lit visible sample is transformed
//! to the image plane of the light, where it becomes a sampling point `(x′, y′)` with its
//! light-space depth `z′`.
//!
//! What is projected is the sample's shadow-ray origin (the surface point offset by its
//! error bound, exactly as the reference offsets it), and each sample keeps that shadow ray
//! for the exact test in the leaves. The plane is orthographic for a directional light, the
//! spot light's own perspective plane, or, for a point light, the cube face its direction
//! falls on (one plane per face: "multiple maps are generally needed for omni-directional
//! light sources").
//!
//! A directional light's samples (without layers) take the block path of `wide.rs`: one
//! shear for every shadow ray, the offset and the projection on arrays of coordinates, with
//! an AVX2 variant chosen at run time — the same operations, so the same bits.

mod wide;

use super::shadow_ray::ShadowRay;
use super::{Buffers, Frame};
use crate::light::{cube_face, pick_up, Light, CUBE_FACES};
use crate::math::{Aabb, RayShear, Vec3};
use rayon::prelude::*;
use wide::Directional;

/// How world points map to one light image plane.
#[derive(Clone, Copy, Debug)]
pub(super) enum Projection {
    /// Orthographic, along a directional light.
    Ortho(Ortho),
    /// Perspective, from a spot light or a point light's cube face.
    Persp(Persp),
}

/// Orthographic along a directional light: `(u, v, depth) = ((p − c)·s, (p − c)·t, (p − c)·w)`
/// with `w` pointing away from the light.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ortho {
    pub(super) c: Vec3,
    pub(super) s: Vec3,
    pub(super) t: Vec3,
    pub(super) w: Vec3,
}

/// Perspective from a light position `l` looking along `f`: with `q = p − l`,
/// `(x, y, z) = (q·s, q·t, q·f)` and `(u, v) = (x/z, y/z)`, depth `z`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Persp {
    pub(super) l: Vec3,
    pub(super) s: Vec3,
    pub(super) t: Vec3,
    pub(super) f: Vec3,
}

impl Ortho {
    /// `(u, v, depth)` of `p`.
    #[inline]
    pub(super) fn coords(&self, p: Vec3) -> [f32; 3] {
        let q = p - self.c;
        [q.dot(self.s), q.dot(self.t), q.dot(self.w)]
    }
}

impl Persp {
    /// `(x, y, z)` of `p`: light space before the division by `z`.
    #[inline]
    pub(super) fn coords(&self, p: Vec3) -> Vec3 {
        let q = p - self.l;
        Vec3::new(q.dot(self.s), q.dot(self.t), q.dot(self.f))
    }
}

impl Projection {
    /// Where `p` falls on the plane; `None` where a perspective projection is undefined
    /// (at or behind the light's plane).
    #[inline]
    fn project(&self, p: Vec3, id: u32) -> Option<Pt> {
        match self {
            Projection::Ortho(o) => {
                let [u, v, z] = o.coords(p);
                Some(Pt { u, v, z, id })
            }
            Projection::Persp(pp) => {
                let q = pp.coords(p);
                let z = q.z;
                let (u, v) = (q.x / z, q.y / z);
                (z > 0.0 && u.is_finite() && v.is_finite()).then_some(Pt { u, v, z, id })
            }
        }
    }
}

/// A sample projected to a light image plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pt {
    pub(super) u: f32,
    pub(super) v: f32,
    /// Light depth (distance along the plane's axis).
    pub(super) z: f32,
    /// Index into the plane's shadow rays.
    pub(super) id: u32,
}

/// The samples of one light image plane, before the BSP is built.
pub(super) struct Plane {
    pub(super) proj: Projection,
    pub(super) pts: Vec<Pt>,
    pub(super) rays: Vec<ShadowRay>,
    /// Scale of the culling tolerance: the scene's diagonal (orthographic), or the farthest
    /// sample plus the farthest scene corner from the light (perspective).
    pub(super) scale: f32,
}

/// The lit samples of a frame, in receiver order: shadow rays, projected points and, for a
/// point light, the cube face of each.
struct Samples {
    rays: Vec<ShadowRay>,
    pts: Vec<Pt>,
    face: Vec<u8>,
}

/// Pixels per block of the transform pass.
const TRANSFORM_BLOCK: usize = 4096;

/// The lit samples' shadow rays, exactly as the reference forms them, each projected by
/// `proj` (or by the cube face of its direction when `proj` is `None`).
fn shadow_rays(
    frame: &Frame,
    proj: Option<&Projection>,
    cube: &[Projection; 6],
    buf: &mut Buffers,
) -> Samples {
    let view = frame.view;
    let light = frame.light;
    let pixels = view.triangle.len();
    let layers = frame.layers;
    // Receivers: the pixels' nearest surfaces, then the layer samples behind them.
    let n = pixels + layers.map_or(0, |l| l.len());
    let lit = |k: usize| match layers {
        Some(l) if k >= pixels => frame.layer_lit(l, k - pixels),
        _ => frame.receiver_lit(k),
    };
    let receiver = |k: usize| match layers {
        Some(l) if k >= pixels => {
            let i = k - pixels;
            (l.surface_point(i), l.normal[i], l.triangle[i])
        }
        _ => (view.surface_point(k), view.normal[k], view.triangle[k]),
    };
    // A directional light's samples, without layers, take the block path: one shear for
    // every ray, the per-sample arithmetic on arrays (the same bits).
    let wide = match (*light, proj, layers) {
        (Light::Directional { to_light }, Some(Projection::Ortho(ortho)), None) => {
            Some(Directional {
                view,
                to_light,
                shear: RayShear::new(to_light),
                ortho: *ortho,
            })
        }
        _ => None,
    };
    let block = |b: usize| b * TRANSFORM_BLOCK..((b + 1) * TRANSFORM_BLOCK).min(n);
    // Count the lit samples of each block, so every block writes its own slice.
    let counts: Vec<usize> = (0..n.div_ceil(TRANSFORM_BLOCK))
        .into_par_iter()
        .map(|b| match &wide {
            Some(d) => block(b).filter(|&k| d.lit(k)).count(),
            None => block(b).filter(|&k| lit(k)).count(),
        })
        .collect();
    let total: usize = counts.iter().sum();
    let placeholder = ShadowRay::new(Vec3::ZERO, Vec3::Z, 0.0, 0, 0);
    let mut rays = buf.rays.take();
    rays.resize(total, placeholder);
    let mut pts = buf.pts.take();
    let origin = Pt {
        u: 0.0,
        v: 0.0,
        z: 0.0,
        id: 0,
    };
    pts.resize(total, origin);
    let mut face = buf.bytes.take();
    face.resize(total, 0);
    let mut jobs = Vec::with_capacity(counts.len());
    {
        let (mut r, mut p, mut f) = (&mut rays[..], &mut pts[..], &mut face[..]);
        let mut first = 0;
        for (b, &c) in counts.iter().enumerate() {
            let (r0, r1) = r.split_at_mut(c);
            let (p0, p1) = p.split_at_mut(c);
            let (f0, f1) = f.split_at_mut(c);
            jobs.push((b, first, r0, p0, f0));
            (r, p, f) = (r1, p1, f1);
            first += c;
        }
    }
    let position = match *light {
        Light::Point { position } | Light::Spot { position, .. } => position,
        Light::Directional { .. } => Vec3::ZERO,
    };
    jobs.into_par_iter().for_each(|(b, first, r, p, f)| {
        if let Some(d) = &wide {
            // Every face byte stays 0: one plane.
            d.block(block(b), first, r, p);
            return;
        }
        let mut j = 0;
        for k in block(b) {
            if !lit(k) {
                continue;
            }
            let (sp, normal, own) = receiver(k);
            let (l, _) = light.shadow_ray(sp.p);
            let o = sp.offset_origin(normal, l);
            let (dir, t_max) = light.shadow_ray(o);
            r[j] = ShadowRay::new(o, dir, t_max, own, k as u32);
            let id = (first + j) as u32;
            let (pt, fc) = match proj {
                Some(proj) => (proj.project(o, id), 0),
                None => {
                    let fc = cube_face(o - position);
                    (cube[fc].project(o, id), fc as u8)
                }
            };
            // A sample the projection cannot place (behind a spot light's plane, or on the
            // light itself) is marked with a non-finite depth for the caller to handle.
            p[j] = pt.unwrap_or(Pt {
                u: 0.0,
                v: 0.0,
                z: f32::NAN,
                id,
            });
            f[j] = fc;
            j += 1;
        }
    });
    Samples { rays, pts, face }
}

/// The cube faces of a point light at `l`, in [`CUBE_FACES`] order. The face axes are signed
/// coordinate axes, so the projection to a face is exact.
fn cube_projections(l: Vec3) -> [Projection; 6] {
    CUBE_FACES.map(|(dir, up)| {
        Projection::Persp(Persp {
            l,
            s: dir.cross(up),
            t: up,
            f: dir,
        })
    })
}

/// The lit samples grouped into light image planes.
pub(super) fn transform(frame: &Frame, buf: &mut Buffers) -> Vec<Plane> {
    let light = frame.light;
    let scene_bounds = frame.scene.bounds;
    match *light {
        Light::Directional { to_light } => {
            let w = -to_light.normalize();
            let s = w.cross(pick_up(w)).normalize();
            let t = s.cross(w);
            let c = scene_bounds.center();
            let proj = Projection::Ortho(Ortho { c, s, t, w });
            let Samples { rays, pts, face } =
                shadow_rays(frame, Some(&proj), &cube_projections(Vec3::ZERO), buf);
            buf.bytes.give(face);
            vec![Plane {
                proj,
                pts,
                rays,
                scale: scene_bounds.diagonal().max(f32::MIN_POSITIVE),
            }]
        }
        Light::Spot {
            position, target, ..
        } => {
            let f = (target - position).normalize();
            let s = f.cross(pick_up(f)).normalize();
            let t = s.cross(f);
            let proj = Projection::Persp(Persp {
                l: position,
                s,
                t,
                f,
            });
            let cube = cube_projections(position);
            let Samples { rays, pts, face } = shadow_rays(frame, Some(&proj), &cube, buf);
            buf.bytes.give(face);
            if pts.iter().all(|p| p.z.is_finite()) {
                let scale = perspective_scale(position, &rays, &scene_bounds);
                vec![Plane {
                    proj,
                    pts,
                    rays,
                    scale,
                }]
            } else {
                // A sample at or behind the spot's own plane (impossible inside its cone,
                // but cheap to be sure of): use the cube of a point light instead.
                buf.rays.give(rays);
                buf.pts.give(pts);
                let samples = shadow_rays(frame, None, &cube, buf);
                cube_planes(position, samples, &scene_bounds, buf)
            }
        }
        Light::Point { position } => {
            let cube = cube_projections(position);
            let samples = shadow_rays(frame, None, &cube, buf);
            cube_planes(position, samples, &scene_bounds, buf)
        }
    }
}

/// The farthest sample plus the farthest scene corner from the light at `l`: the distances
/// a perspective plane's culling tolerance scales with.
fn perspective_scale(l: Vec3, rays: &[ShadowRay], scene: &Aabb) -> f32 {
    let far_sample = rays
        .par_iter()
        .with_min_len(4096)
        .map(|r| (Vec3::from_array(r.o) - l).length())
        .reduce(|| 0.0f32, f32::max);
    let far_corner = scene
        .corners()
        .iter()
        .map(|c| (*c - l).length())
        .fold(0.0f32, f32::max);
    (far_sample + far_corner).max(f32::MIN_POSITIVE)
}

/// Splits a point light's samples by cube face (faces without samples are left out).
fn cube_planes(l: Vec3, samples: Samples, scene: &Aabb, buf: &mut Buffers) -> Vec<Plane> {
    let Samples { rays, pts, face } = samples;
    let scale = perspective_scale(l, &rays, scene);
    let cube = cube_projections(l);
    let mut count = [0usize; 6];
    for &f in &face {
        count[f as usize] += 1;
    }
    let mut planes: Vec<Plane> = (0..6)
        .map(|f| {
            let (mut pts, mut rays) = (buf.pts.take(), buf.rays.take());
            pts.reserve(count[f]);
            rays.reserve(count[f]);
            Plane {
                proj: cube[f],
                pts,
                rays,
                scale,
            }
        })
        .collect();
    for ((r, p), &f) in rays.iter().zip(&pts).zip(&face) {
        let (r, mut p) = (*r, *p);
        let plane = &mut planes[f as usize];
        p.id = plane.rays.len() as u32;
        if !p.z.is_finite() {
            // The sample sits on the light itself: any point of the face will do, the
            // tolerance and the exact test decide.
            p = Pt {
                u: 0.0,
                v: 0.0,
                z: 0.0,
                id: p.id,
            };
        }
        plane.rays.push(r);
        plane.pts.push(p);
    }
    buf.rays.give(rays);
    buf.pts.give(pts);
    buf.bytes.give(face);
    let (kept, empty): (Vec<Plane>, Vec<Plane>) =
        planes.into_iter().partition(|p| !p.pts.is_empty());
    for p in empty {
        buf.rays.give(p.rays);
        buf.pts.give(p.pts);
    }
    kept
}
