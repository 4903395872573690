//! The shadow map of `psm` in post-perspective space (Stamminger & Drettakis 2002,
//! Section 2: "generate a standard shadow map in this space by rendering a view from the
//! transformed light source"): the map's transforms, and the rasterization of the scene
//! into it.
//!
//! Every triangle is clipped in world space to the virtual camera's depths beyond
//! [`CLIP_DEPTH_FRACTION`] of its near plane (the body lies beyond the near plane), divided
//! into post-perspective space and rasterized by the shared rasterizer with
//! `clip_from_post · post_from_world` (one matrix, then the division by the virtual
//! camera's `w`). The stored depth is the linear post-space depth from the map's near
//! plane, negated for an inverted light so that the min-test keeps the surface farthest
//! from `q`; it is affine on every post-space triangle, so the rasterizer's
//! perspective-correct interpolation is exact.

use super::fit::MapFit;
use super::post_space::PostLight;
use super::Setup;
use crate::frame::Frame;
use crate::math::{Mat4, Vec3, Vec4};
use crate::raster::{self, SetupTriangle};
use glam::DMat4;
use rayon::prelude::*;

/// Triangles are clipped to depths beyond this fraction of the virtual near plane before
/// the perspective division. The body lies beyond the near plane, so anything nearer
/// cannot matter; smaller values keep more irrelevant geometry with huge post-space images.
pub const CLIP_DEPTH_FRACTION: f32 = 0.5;

/// One post-perspective shadow map.
#[derive(Clone, Debug)]
pub struct PostMap {
    /// World to the map's clip space up to the positive factor `w_p` (the virtual camera's
    /// clip `w`): `clip_from_post · post_from_world`, composed in f64.
    pub clip_from_world: Mat4,
    /// The post-space linear depth beyond the near plane times `w_p`, as a row on
    /// homogeneous world points.
    pub depth_world: Vec4,
    /// Texel size in post units: absolute (orthographic) or per unit distance from `q`.
    pub texel: f32,
    /// Distance of the near plane from `q` (0 for orthographic maps).
    pub near: f32,
    /// The map's depth range, far minus near plane: the linear depths of what the map
    /// holds lie in `0..span`.
    pub span: f32,
    /// True for a map along a post-space directional light.
    pub orthographic: bool,
    /// Stored depths (negated for inverted lights), `+inf` where empty.
    pub depth: Vec<f32>,
}

impl PostMap {
    /// The map of the frustum `fit`, joined to the world; its depths are still empty.
    pub(super) fn new(fit: MapFit, post_from_world: &DMat4) -> PostMap {
        PostMap {
            clip_from_world: (fit.clip_from_post * *post_from_world).as_mat4(),
            depth_world: (post_from_world.transpose() * fit.depth_row).as_vec4(),
            texel: fit.texel as f32,
            near: fit.near as f32,
            span: fit.span as f32,
            orthographic: fit.orthographic,
            depth: Vec::new(),
        }
    }

    /// Clip coordinates (divided by `w_p`) and linear depth of a world point whose
    /// virtual-camera `w` has reciprocal `inv_wp`: the one formula for map vertices and
    /// receivers alike.
    #[inline]
    pub fn transform(&self, p: Vec4, inv_wp: f32) -> (Vec4, f32) {
        (
            self.clip_from_world * p * inv_wp,
            self.depth_world.dot(p) * inv_wp,
        )
    }

    /// Post-space size of one texel at linear depth `depth` (beyond the near plane).
    #[inline]
    pub fn texel_size(&self, depth: f32) -> f32 {
        if self.orthographic {
            self.texel
        } else {
            self.texel * (depth + self.near).max(self.near)
        }
    }
}

/// Clips a world triangle to `depth >= clip` (depth = `w_row · (p, 1)`), returning 0, 1 or
/// 2 triangles.
fn clip_triangle(t: [Vec3; 3], w_row: Vec4, clip: f32, out: &mut Vec<[Vec3; 3]>) {
    let d = t.map(|p| w_row.dot(p.extend(1.0)) - clip);
    let mut poly: Vec<Vec3> = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (t[i], t[(i + 1) % 3]);
        let (da, db) = (d[i], d[(i + 1) % 3]);
        if da >= 0.0 {
            poly.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let (pi, di, po, dout) = if da >= 0.0 {
                (a, da, b, db)
            } else {
                (b, db, a, da)
            };
            poly.push(pi + (po - pi) * (di / (di - dout)));
        }
    }
    for k in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}

/// A piece of a triangle cut by the clip plane: the source triangle and the piece's
/// world-space vertices.
pub(super) type Piece = (u32, [Vec3; 3]);

/// The pieces of the triangles that cross the clip plane `w_row · p = clip`, cut in world
/// space (the whole ones go to the rasterizer as they are).
pub(super) fn clipped_pieces(frame: &Frame, setup: &Setup) -> Vec<Piece> {
    let scene = frame.scene;
    let (w_row, clip) = (setup.w_row, setup.clip_depth);
    if scene
        .bounds
        .corners()
        .iter()
        .all(|p| w_row.dot(p.extend(1.0)) >= clip)
    {
        return Vec::new();
    }
    const CHUNK: usize = 8192;
    let parts: Vec<Vec<Piece>> = (0..scene.len().div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            let mut cut = Vec::new();
            for i in c * CHUNK..((c + 1) * CHUNK).min(scene.len()) {
                let t = scene.triangle(i);
                let d = t.map(|p| w_row.dot(p.extend(1.0)));
                let lo = d[0].min(d[1]).min(d[2]);
                let hi = d[0].max(d[1]).max(d[2]);
                if lo < clip && hi >= clip {
                    cut.clear();
                    clip_triangle(t, w_row, clip, &mut cut);
                    out.extend(cut.iter().map(|&p| (i as u32, p)));
                }
            }
            out
        })
        .collect();
    parts.concat()
}

/// Rasterizes the scene (whole triangles in front of the clip plane, and `pieces`) into
/// one post-perspective map.
pub(super) fn render_post_map(
    frame: &Frame,
    setup: &Setup,
    map: &PostMap,
    pieces: &[Piece],
    res: u32,
) -> Vec<f32> {
    let scene = frame.scene;
    let (w_row, clip) = (setup.w_row, setup.clip_depth);
    let sign = if setup.post.light == PostLight::Inverted {
        -1.0f32
    } else {
        1.0
    };
    let n = scene.len();
    let setups: Vec<SetupTriangle> = raster::setup(n + pieces.len(), res, res, |i| {
        let t = if i < n {
            scene.triangle(i)
        } else {
            pieces[i - n].1
        };
        let h = t.map(|p| p.extend(1.0));
        let wp = h.map(|h| w_row.dot(h));
        if i < n && wp.iter().any(|&w| w < clip) {
            // Behind the clip plane, or cut into `pieces`.
            return ([Vec4::NAN; 3], [0.0; 3]);
        }
        let v: [(Vec4, f32); 3] = std::array::from_fn(|k| map.transform(h[k], 1.0 / wp[k]));
        (
            [v[0].0, v[1].0, v[2].0],
            [sign * v[0].1, sign * v[1].1, sign * v[2].1],
        )
    });
    // An alpha-masked caster reads its mask at the fragment's world point. The rasterizer's
    // barycentrics `b'` are those of the post-perspective triangle, whose vertices were
    // divided by `wp` first: the world triangle's are `b'_k / wp_k`, normalized. A piece
    // reads the mask at its point in the whole triangle.
    let masked = scene.has_alpha_masks();
    let world = |t: [Vec3; 3], b: [f32; 3]| {
        let q: [f32; 3] = std::array::from_fn(|k| b[k] / w_row.dot(t[k].extend(1.0)));
        let s = q[0] + q[1] + q[2];
        q.map(|x| x / s)
    };
    let cut_out = |f: raster::Fragment| {
        let i = f.id as usize;
        if !masked {
            false
        } else if i < n {
            scene.material_of(i).alpha_mask.is_some()
                && scene.cut_out(i, world(scene.triangle(i), f.bary()))
        } else {
            let (src, p) = pieces[i - n];
            let b = world(p, f.bary());
            scene.cut_out_at(src as usize, p[0] * b[0] + p[1] * b[1] + p[2] * b[2])
        }
    };
    let tiles = raster::rasterize(
        &setups,
        res,
        res,
        |r| vec![f32::INFINITY; (r.width() * r.height()) as usize],
        |d: &mut Vec<f32>, r, f| {
            let k = ((f.y - r.y0) * r.width() + (f.x - r.x0)) as usize;
            if f.depth < d[k] && !cut_out(f) {
                d[k] = f.depth;
            }
        },
    );
    let mut out = vec![f32::INFINITY; res as usize * res as usize];
    for (r, d) in tiles {
        for y in r.y0..r.y1 {
            let src = ((y - r.y0) * r.width()) as usize;
            let dst = (y * res + r.x0) as usize;
            out[dst..dst + r.width() as usize].copy_from_slice(&d[src..src + r.width() as usize]);
        }
    }
    out
}
