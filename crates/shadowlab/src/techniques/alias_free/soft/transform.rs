//! Stage one of exact soft alias-free shadows, the soft counterpart of the hard
//! technique's *transform* (Aila & Laine 2004, Section 3): every view sample's shadow-ray
//! origin (the surface point offset by its error bound, exactly as the reference offsets
//! it towards any light sample in front of the surface) is projected from the light's
//! centre to the light image planes the hard technique uses for a punctual light there:
//! the six cube faces about a rectangle's, disk's or sphere's centre, the orthographic
//! plane along a distant light's axis.
//!
//! Here too each sample gets its *lit mask*: the light samples the reference would trace
//! at all (in front of the surface, inside a sized spot's cone). When every corner of the
//! light's bounding shape is in front of the surface by a margin, all are; otherwise each
//! sample is decided by the reference's own [`shadow_ray`]. Samples with an empty mask
//! stay out of the planes (their shadow term is 0).

use super::super::shadow_ray::ShadowRay;
use super::super::transform::{Ortho, Persp, Plane, Projection, Pt};
use super::super::Buffers;
use super::samples::{bounding_corners, LightSamples};
use super::SOFT_TOLERANCE;
use crate::area_light::AreaLight;
use crate::frame::Frame;
use crate::light::{cube_face, pick_up, CUBE_FACES};
use crate::math::Vec3;
use crate::soft_reference::shadow_ray;
use rayon::prelude::*;

/// The view samples' lit masks, `words` per pixel (all zero for pixels that take no part).
pub(super) struct LitMasks {
    pub(super) words: usize,
    pub(super) bits: Vec<u64>,
}

impl LitMasks {
    /// The mask of pixel `k`.
    pub(super) fn of(&self, k: usize) -> &[u64] {
        &self.bits[k * self.words..(k + 1) * self.words]
    }
}

/// The lit mask of pixel `k` into `mask`; false when it is empty.
fn lit_mask(
    frame: &Frame,
    area: &AreaLight,
    ls: &LightSamples,
    corners: &[Vec3],
    k: usize,
    mask: &mut [u64],
) -> bool {
    let view = frame.view;
    if !view.covered(k) {
        return false;
    }
    let sp = view.surface_point(k);
    let n = view.normal[k];
    if !AreaLight::in_cone(frame.light, sp.p) {
        return false;
    }
    let w = ls.w;
    let size = sp.p.length() + corners.iter().map(|c| c.length()).fold(0.0, f32::max);
    let all_front = corners
        .iter()
        .all(|&c| n.dot(c - sp.p * w) > SOFT_TOLERANCE * size);
    if all_front {
        for (i, word) in mask.iter_mut().enumerate() {
            let bits = (ls.len() - i * 64).min(64);
            *word = if bits == 64 { !0 } else { (1u64 << bits) - 1 };
        }
        return true;
    }
    let mut any = false;
    for (i, &uv) in ls.uvs.iter().enumerate() {
        if shadow_ray(area, &sp, n, uv).is_some() {
            mask[i / 64] |= 1 << (i % 64);
            any = true;
        }
    }
    any
}

/// The planes of the view samples that see some light sample, and every pixel's lit mask.
pub(super) fn transform(
    frame: &Frame,
    area: &AreaLight,
    ls: &LightSamples,
    buf: &mut Buffers,
) -> (Vec<Plane>, LitMasks) {
    let view = frame.view;
    let pixels = view.triangle.len();
    let words = ls.words;
    let corners = bounding_corners(area);
    let mut bits = vec![0u64; pixels * words];
    let lit: Vec<bool> = bits
        .par_chunks_mut(words)
        .with_min_len(1024)
        .enumerate()
        .map(|(k, m)| lit_mask(frame, area, ls, &corners, k, m))
        .collect();
    let origin = |k: usize| {
        let sp = view.surface_point(k);
        // Every traced sample lies in front of the surface: the offset side is the
        // normal's (as `offset_origin` picks it for such a direction).
        sp.offset_origin(view.normal[k], view.normal[k])
    };
    let scene_bounds = frame.scene.bounds;
    let planes = match *area {
        AreaLight::Distant { to_light, .. } => {
            let w = -to_light.normalize();
            let s = w.cross(pick_up(w)).normalize();
            let t = s.cross(w);
            let o = Ortho {
                c: scene_bounds.center(),
                s,
                t,
                w,
            };
            let mut plane = Plane {
                proj: Projection::Ortho(o),
                pts: buf.pts.take(),
                rays: buf.rays.take(),
                scale: scene_bounds.diagonal().max(f32::MIN_POSITIVE),
            };
            for k in (0..pixels).filter(|&k| lit[k]) {
                let p = origin(k);
                let [u, v, z] = o.coords(p);
                push(&mut plane, p, u, v, z, view.triangle[k], k);
            }
            vec![plane]
        }
        _ => cube_planes(frame, centre(area), &lit, &origin, buf),
    };
    (planes, LitMasks { words, bits })
}

/// Appends one sample to `plane`: its projection and a ray record carrying its origin,
/// its own triangle and its pixel (what the soft leaves read of it).
fn push(plane: &mut Plane, o: Vec3, u: f32, v: f32, z: f32, own: u32, k: usize) {
    let id = plane.rays.len() as u32;
    plane
        .rays
        .push(ShadowRay::new(o, Vec3::Z, 0.0, own, k as u32));
    plane.pts.push(Pt { u, v, z, id });
}

/// The samples of a light centred at `l`, split by the cube face their direction from `l`
/// falls on (faces without samples are left out).
fn cube_planes(
    frame: &Frame,
    l: Vec3,
    lit: &[bool],
    origin: &(dyn Fn(usize) -> Vec3 + Sync),
    buf: &mut Buffers,
) -> Vec<Plane> {
    let view = frame.view;
    let far_corner = frame
        .scene
        .bounds
        .corners()
        .iter()
        .map(|c| (*c - l).length())
        .fold(0.0f32, f32::max);
    let faces = CUBE_FACES.map(|(dir, up)| Persp {
        l,
        s: dir.cross(up),
        t: up,
        f: dir,
    });
    let mut planes: Vec<Plane> = faces
        .iter()
        .map(|&pp| Plane {
            proj: Projection::Persp(pp),
            pts: buf.pts.take(),
            rays: buf.rays.take(),
            scale: 0.0,
        })
        .collect();
    let mut far_sample = 0.0f32;
    for k in (0..lit.len()).filter(|&k| lit[k]) {
        let o = origin(k);
        far_sample = far_sample.max((o - l).length());
        let f = cube_face(o - l);
        let plane = &mut planes[f];
        let q = faces[f].coords(o);
        let (u, v) = (q.x / q.z, q.y / q.z);
        if q.z > 0.0 && u.is_finite() && v.is_finite() {
            push(plane, o, u, v, q.z, view.triangle[k], k);
        } else {
            // On the light's centre: any point of the face will do, the footprint's
            // depth test and the exact classification decide.
            push(plane, o, 0.0, 0.0, 0.0, view.triangle[k], k);
        }
    }
    let scale = (far_sample + far_corner).max(f32::MIN_POSITIVE);
    let (kept, empty): (Vec<Plane>, Vec<Plane>) =
        planes.into_iter().partition(|p| !p.pts.is_empty());
    for p in empty {
        buf.rays.give(p.rays);
        buf.pts.give(p.pts);
    }
    kept.into_iter().map(|p| Plane { scale, ..p }).collect()
}

/// The centre of a light with a position.
fn centre(area: &AreaLight) -> Vec3 {
    match *area {
        AreaLight::Rect { centre, .. }
        | AreaLight::Disk { centre, .. }
        | AreaLight::Sphere { centre, .. } => centre,
        AreaLight::Distant { to_light, .. } => to_light,
    }
}
