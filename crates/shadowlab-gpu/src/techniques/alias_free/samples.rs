//! The sub-pixel samples of `samples` > 1: every covered pixel's primary rays through the
//! library's grid of sub-pixel positions, traced to their closest surface exactly as the
//! N-spp reference traces them (the library's BVH, the lower triangle index on equal
//! distance), each hit becoming a sample with its error-bounded point and the face normal
//! turned towards the viewer. A pixel whose rays all miss keeps its camera-pass sample,
//! as the reference keeps the centre's value. The samples lie pixel by pixel in the
//! pattern's order, so the shader's mean adds them in the reference's order.

use crate::upload::VIEW_STRIDE;
use rayon::prelude::*;
use shadowlab::error::Result;
use shadowlab::math::Vec3;
use shadowlab::reference::{facing_normal, Reference};
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::Frame;

/// The samples, [`VIEW_STRIDE`] words each (position, error bound, normal, triangle), and
/// where each pixel's run starts (one more entry than pixels).
pub(super) struct SubSamples {
    /// The samples' words.
    pub(super) words: Vec<u32>,
    /// Pixel `k`'s samples are `start[k]..start[k + 1]`.
    pub(super) start: Vec<u32>,
}

fn push(out: &mut Vec<u32>, p: Vec3, err: Vec3, n: Vec3, tri: u32) {
    for v in [p, err, n] {
        out.extend(v.to_array().map(f32::to_bits));
    }
    out.push(tri);
}

/// The sub-pixel samples of `frame` at `spp` positions a pixel.
pub(super) fn sub_samples(frame: &Frame, spp: u32) -> Result<SubSamples> {
    let positions = pattern(PatternKind::Grid, spp)?;
    let reference = Reference::build(frame.scene);
    let view = frame.view;
    let rays = frame.camera.rays();
    let (w, h) = (view.width, view.height);
    let rows: Vec<(Vec<u32>, Vec<u32>)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut words = Vec::new();
            let mut counts = Vec::with_capacity(w as usize);
            for x in 0..w {
                let k = (y * w + x) as usize;
                let before = words.len();
                if view.covered(k) {
                    for s in &positions {
                        let (o, d) = rays.ray(x as f32 + s.x, y as f32 + s.y);
                        if let Some(hit) = reference.closest_hit(o, d) {
                            let n = facing_normal(frame.scene, hit.triangle, d);
                            push(&mut words, hit.point.p, hit.point.error, n, hit.triangle);
                        }
                    }
                    if words.len() == before {
                        let sp = view.surface_point(k);
                        push(&mut words, sp.p, sp.error, view.normal[k], view.triangle[k]);
                    }
                }
                counts.push(((words.len() - before) / VIEW_STRIDE) as u32);
            }
            (words, counts)
        })
        .collect();
    let mut start = Vec::with_capacity((w * h) as usize + 1);
    let mut words = Vec::new();
    let mut total = 0u32;
    for (wds, counts) in rows {
        for c in counts {
            start.push(total);
            total += c;
        }
        words.extend(wds);
    }
    start.push(total);
    Ok(SubSamples { words, start })
}
