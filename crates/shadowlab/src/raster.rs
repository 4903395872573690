//! The one rasterizer: the camera pass and every light-space map go through it.
//!
//! Tiled and multi-threaded: triangles are clipped in homogeneous space (near, far and a
//! guard band), snapped to a fixed-point grid of 1/256 pixel, binned into 64×64 tiles,
//! and each tile is rasterized by one thread, visiting its triangles in index order —
//! so the output is bit-identical for any thread count. Coverage uses exact integer edge
//! functions with a top-left fill rule: a pixel centre on an edge shared by two triangles
//! belongs to exactly one of them (watertight, no double hits). The per-vertex depth
//! attribute and the barycentrics of the source triangle (which alpha-masked casters read
//! their texture through) are interpolated perspective-correctly (through 1/w).

use crate::math::{orient2d_i64, Vec4};
use rayon::prelude::*;

mod buffers;
pub use buffers::{
    coverage_count, depth_buffer, depth_buffer_where, nearest_ids_where, DepthBuffer, NO_TRIANGLE,
};

/// Side of a square tile in pixels.
pub const TILE: u32 = 64;
/// Sub-pixel precision: 8 fractional bits.
const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: f32 = (1 << SUBPIXEL_BITS) as f32;
/// Screen coordinates are kept within ±2¹⁶ pixels by the guard band, so edge functions on
/// 24-bit fixed-point coordinates fit in i64 with room to spare.
const GUARD_PIXELS: f32 = 32768.0;
/// The largest map or image side the rasterizer accepts.
pub const MAX_RASTER_SIDE: u32 = 32768;

/// A triangle after clipping, projection and snapping, ready to rasterize.
#[derive(Clone, Copy, Debug)]
pub struct SetupTriangle {
    /// Index of the source triangle.
    pub id: u32,
    /// Fixed-point screen positions (1/256 pixel).
    v: [[i64; 2]; 3],
    /// Per-edge bias implementing the fill rule (0 or −1).
    bias: [i64; 3],
    /// Twice the signed area (positive after reordering).
    area: i64,
    /// 1/w at each vertex.
    inv_w: [f32; 3],
    /// depth/w at each vertex.
    d_over_w: [f32; 3],
    /// The source triangle's barycentrics of vertices 1 and 2, over w, at each vertex.
    b_over_w: [[f32; 2]; 3],
    /// Pixel bounding box, inclusive min, exclusive max.
    bbox: [u32; 4],
}

/// One covered pixel, handed to a tile's fragment function.
#[derive(Clone, Copy, Debug)]
pub struct Fragment {
    /// Pixel column.
    pub x: u32,
    /// Pixel row (0 at the top).
    pub y: u32,
    /// Source triangle index.
    pub id: u32,
    /// Interpolated depth attribute.
    pub depth: f32,
    /// 1/w at the pixel centre.
    inv_w: f64,
    /// The source triangle's barycentrics of vertices 1 and 2, over w, at the pixel centre.
    b_over_w: [f64; 2],
}

impl Fragment {
    /// Barycentrics of the pixel centre in the source triangle (weights of its vertices
    /// 0, 1, 2), interpolated perspective-correctly through clipping. Worked out on demand:
    /// only alpha-masked casters read them, and two divisions a fragment would otherwise
    /// fall on every map.
    #[inline]
    pub fn bary(&self) -> [f32; 3] {
        let b1 = (self.b_over_w[0] / self.inv_w) as f32;
        let b2 = (self.b_over_w[1] / self.inv_w) as f32;
        [1.0 - b1 - b2, b1, b2]
    }
}

/// A rectangle of pixels, `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileRect {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// One past the right column.
    pub x1: u32,
    /// One past the bottom row.
    pub y1: u32,
}

impl TileRect {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }
    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }
}

#[derive(Clone, Copy)]
struct ClipVert {
    c: Vec4,
    d: f32,
    b: [f32; 2],
}

fn lerp_vert(a: ClipVert, b: ClipVert, t: f32) -> ClipVert {
    ClipVert {
        c: a.c + (b.c - a.c) * t,
        d: a.d + (b.d - a.d) * t,
        b: [
            a.b[0] + (b.b[0] - a.b[0]) * t,
            a.b[1] + (b.b[1] - a.b[1]) * t,
        ],
    }
}

/// Clips a polygon against `dist(v) >= 0`. Intersections are always computed from the
/// inside vertex towards the outside one, so two triangles sharing an edge get the same
/// clipped vertex on it.
fn clip_polygon(poly: &[ClipVert], out: &mut Vec<ClipVert>, dist: impl Fn(Vec4) -> f32) {
    out.clear();
    let n = poly.len();
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        let da = dist(a.c);
        let db = dist(b.c);
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let v = if da >= 0.0 {
                lerp_vert(a, b, da / (da - db))
            } else {
                lerp_vert(b, a, db / (db - da))
            };
            out.push(v);
        }
    }
}

/// Prepares triangles for rasterization at `width × height`: clip-space vertices and a
/// per-vertex depth attribute come from `fetch(i)` for `i in 0..count`. Triangles that
/// are degenerate, outside the view or non-finite produce nothing.
pub fn setup<F>(count: usize, width: u32, height: u32, fetch: F) -> Vec<SetupTriangle>
where
    F: Fn(usize) -> ([Vec4; 3], [f32; 3]) + Sync,
{
    const CHUNK: usize = 4096;
    let chunks: Vec<Vec<SetupTriangle>> = (0..count.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut setup = TriangleSetup::new(width, height);
            for i in c * CHUNK..((c + 1) * CHUNK).min(count) {
                let (clip, d) = fetch(i);
                setup.add(i as u32, clip, d);
            }
            setup.out
        })
        .collect();
    chunks.concat()
}

/// One worker's triangle set-up: the target size, the clipper's two scratch polygons and
/// the set-up triangles made so far.
struct TriangleSetup {
    width: u32,
    height: u32,
    a: Vec<ClipVert>,
    b: Vec<ClipVert>,
    out: Vec<SetupTriangle>,
}

impl TriangleSetup {
    fn new(width: u32, height: u32) -> Self {
        TriangleSetup {
            width,
            height,
            a: Vec::with_capacity(12),
            b: Vec::with_capacity(12),
            out: Vec::new(),
        }
    }

    /// Clips triangle `id` (clip-space corners, per-vertex depth attribute) against the
    /// view volume and its guard band, then sets up each piece of the fan it leaves.
    fn add(&mut self, id: u32, clip: [Vec4; 3], d: [f32; 3]) {
        let (width, height) = (self.width, self.height);
        let (a, b) = (&mut self.a, &mut self.b);
        if !clip.iter().all(|c| c.is_finite()) || !d.iter().all(|x| x.is_finite()) {
            return;
        }
        let gx = (GUARD_PIXELS / width as f32).max(1.0);
        let gy = (GUARD_PIXELS / height as f32).max(1.0);
        // Trivial reject against each plane; trivial accept when inside all.
        let planes: [&dyn Fn(Vec4) -> f32; 6] = [
            &|c: Vec4| c.z,
            &|c: Vec4| c.w - c.z,
            &|c: Vec4| c.x + gx * c.w,
            &|c: Vec4| gx * c.w - c.x,
            &|c: Vec4| c.y + gy * c.w,
            &|c: Vec4| gy * c.w - c.y,
        ];
        let mut inside_all = true;
        for p in &planes {
            let ds = clip.map(p);
            if ds.iter().all(|&x| x < 0.0) {
                return;
            }
            if ds.iter().any(|&x| x < 0.0) {
                inside_all = false;
            }
        }
        a.clear();
        const CORNERS: [[f32; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        for k in 0..3 {
            a.push(ClipVert {
                c: clip[k],
                d: d[k],
                b: CORNERS[k],
            });
        }
        if !inside_all {
            for p in &planes {
                clip_polygon(a, b, p);
                std::mem::swap(a, b);
                if a.len() < 3 {
                    return;
                }
            }
        }
        // Project and snap every polygon vertex once, then fan-triangulate.
        let mut verts = [([0i64; 2], 0f32, 0f32, [0f32; 2]); 12];
        let n = a.len().min(12);
        for k in 0..n {
            let v = a[k];
            let iw = 1.0 / v.c.w;
            let sx = (v.c.x * iw * 0.5 + 0.5) * width as f32;
            let sy = (0.5 - v.c.y * iw * 0.5) * height as f32;
            let fx = (sx * SUBPIXEL).round() as i64;
            let fy = (sy * SUBPIXEL).round() as i64;
            verts[k] = ([fx, fy], iw, v.d * iw, [v.b[0] * iw, v.b[1] * iw]);
        }
        for k in 1..n - 1 {
            push_triangle(
                id,
                [verts[0], verts[k], verts[k + 1]],
                width,
                height,
                &mut self.out,
            );
        }
    }
}

fn push_triangle(
    id: u32,
    mut t: [([i64; 2], f32, f32, [f32; 2]); 3],
    width: u32,
    height: u32,
    out: &mut Vec<SetupTriangle>,
) {
    let mut area = orient2d_i64(t[0].0, t[1].0, t[2].0);
    if area == 0 {
        return;
    }
    if area < 0 {
        t.swap(1, 2);
        area = -area;
    }
    let v = [t[0].0, t[1].0, t[2].0];
    // Edge k is opposite vertex k: from v[k+1] to v[k+2]. A pixel centre exactly on an
    // edge belongs to the triangle only when the edge is an "owner" edge: pointing down
    // (dy > 0), or horizontal and pointing left. With positive area in y-down screen
    // coordinates these are the left and top edges — the top-left rule. Reversing an edge
    // flips the answer, so of two triangles sharing an edge exactly one owns each point on
    // it: no cracks and no double hits.
    let mut bias = [0i64; 3];
    for k in 0..3 {
        let a = v[(k + 1) % 3];
        let b = v[(k + 2) % 3];
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let owner = dy > 0 || (dy == 0 && dx < 0);
        bias[k] = if owner { 0 } else { -1 };
    }
    let s = SUBPIXEL as i64;
    let minx = v.iter().map(|p| p[0]).min().unwrap();
    let maxx = v.iter().map(|p| p[0]).max().unwrap();
    let miny = v.iter().map(|p| p[1]).min().unwrap();
    let maxy = v.iter().map(|p| p[1]).max().unwrap();
    // Pixel centres at (px + 0.5): covered columns satisfy px*s + s/2 in [minx, maxx].
    let px0 = (minx - s / 2).div_euclid(s) + 1;
    let px1 = (maxx - s / 2).div_euclid(s) + 1;
    let py0 = (miny - s / 2).div_euclid(s) + 1;
    let py1 = (maxy - s / 2).div_euclid(s) + 1;
    let clampx = |x: i64| x.clamp(0, width as i64) as u32;
    let clampy = |y: i64| y.clamp(0, height as i64) as u32;
    let bbox = [clampx(px0), clampy(py0), clampx(px1), clampy(py1)];
    if bbox[0] >= bbox[2] || bbox[1] >= bbox[3] {
        return;
    }
    out.push(SetupTriangle {
        id,
        v,
        bias,
        area,
        inv_w: [t[0].1, t[1].1, t[2].1],
        d_over_w: [t[0].2, t[1].2, t[2].2],
        b_over_w: [t[0].3, t[1].3, t[2].3],
        bbox,
    });
}

/// Bins set-up triangles into tiles; each bin lists triangle positions in order.
fn bin(tris: &[SetupTriangle], tiles_x: u32, tiles_y: u32) -> Vec<Vec<u32>> {
    let mut bins = vec![Vec::new(); (tiles_x * tiles_y) as usize];
    for (k, t) in tris.iter().enumerate() {
        let tx0 = t.bbox[0] / TILE;
        let ty0 = t.bbox[1] / TILE;
        let tx1 = (t.bbox[2] - 1) / TILE;
        let ty1 = (t.bbox[3] - 1) / TILE;
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                bins[(ty * tiles_x + tx) as usize].push(k as u32);
            }
        }
    }
    bins
}

/// Rasterizes `tris` over a `width × height` target. For each 64×64 tile (in parallel),
/// `new_state` makes the tile's state and `fragment` is called for each covered pixel of
/// each triangle, triangles in index order. Returns every tile's rectangle and state.
pub fn rasterize<S, N, F>(
    tris: &[SetupTriangle],
    width: u32,
    height: u32,
    new_state: N,
    fragment: F,
) -> Vec<(TileRect, S)>
where
    S: Send,
    N: Fn(TileRect) -> S + Sync,
    F: Fn(&mut S, &TileRect, Fragment) + Sync,
{
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    let bins = bin(tris, tiles_x, tiles_y);
    bins.par_iter()
        .enumerate()
        .map(|(k, list)| {
            let tx = k as u32 % tiles_x;
            let ty = k as u32 / tiles_x;
            let rect = TileRect {
                x0: tx * TILE,
                y0: ty * TILE,
                x1: ((tx + 1) * TILE).min(width),
                y1: ((ty + 1) * TILE).min(height),
            };
            let mut state = new_state(rect);
            for &ti in list {
                raster_triangle(&tris[ti as usize], &rect, &mut |f| {
                    fragment(&mut state, &rect, f)
                });
            }
            (rect, state)
        })
        .collect()
}

#[inline]
fn raster_triangle(t: &SetupTriangle, rect: &TileRect, emit: &mut impl FnMut(Fragment)) {
    let x0 = t.bbox[0].max(rect.x0);
    let x1 = t.bbox[2].min(rect.x1);
    let y0 = t.bbox[1].max(rect.y0);
    let y1 = t.bbox[3].min(rect.y1);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let s = SUBPIXEL as i64;
    let v = t.v;
    // Edge function k at point p: orient2d(v[k+1], v[k+2], p), stepped incrementally.
    let mut a = [0i64; 3];
    let mut b = [0i64; 3];
    let mut row = [0i64; 3];
    let p0 = [x0 as i64 * s + s / 2, y0 as i64 * s + s / 2];
    for k in 0..3 {
        let va = v[(k + 1) % 3];
        let vb = v[(k + 2) % 3];
        // orient(va, vb, p) = (vb.x-va.x)(p.y-va.y) - (vb.y-va.y)(p.x-va.x)
        a[k] = -(vb[1] - va[1]) * s; // per +1 pixel in x
        b[k] = (vb[0] - va[0]) * s; // per +1 pixel in y
        row[k] = orient2d_i64(va, vb, p0) + t.bias[k];
    }
    // 1/w and depth/w are affine in the pixel: with the weights w_k = (e_k − bias_k)/area
    // and w₂ = 1 − w₀ − w₁, an attribute is v₂ + w₀(v₀ − v₂) + w₁(v₁ − v₂). Its value at a
    // row's first pixel and its step per pixel are found in f64: a fragment costs two
    // multiply-adds and a division.
    let inv_area = 1.0 / t.area as f64;
    let attribute = |v: [f32; 3]| {
        let [v0, v1, v2] = v.map(f64::from);
        let (g0, g1) = ((v0 - v2) * inv_area, (v1 - v2) * inv_area);
        let at = move |e: &[i64; 3]| {
            v2 + (e[0] - t.bias[0]) as f64 * g0 + (e[1] - t.bias[1]) as f64 * g1
        };
        (at, a[0] as f64 * g0 + a[1] as f64 * g1)
    };
    let (inv_w_at, inv_w_step) = attribute(t.inv_w);
    let (dw_at, dw_step) = attribute(t.d_over_w);
    let bw = &t.b_over_w;
    let (b1w_at, b1w_step) = attribute([bw[0][0], bw[1][0], bw[2][0]]);
    let (b2w_at, b2w_step) = attribute([bw[0][1], bw[1][1], bw[2][1]]);
    // Wide boxes walk only each row's covered span, found exactly from the edge functions;
    // narrow ones test every pixel, which is cheaper than the three divisions a span takes.
    let spans = x1 - x0 > SPAN_MIN_WIDTH;
    for y in y0..y1 {
        let (xs, xe) = if spans {
            covered_span(&row, &a, x1 - x0)
        } else {
            (0, x1 - x0)
        };
        let mut e: [i64; 3] = std::array::from_fn(|k| row[k] + a[k] * xs as i64);
        let (inv_w0, dw0) = (inv_w_at(&e), dw_at(&e));
        let (b1w0, b2w0) = (b1w_at(&e), b2w_at(&e));
        let mut i = 0.0f64;
        let mut fragment = |x: u32, i: f64| {
            let inv_w = inv_w0 + inv_w_step * i;
            let depth = ((dw0 + dw_step * i) / inv_w) as f32;
            emit(Fragment {
                x,
                y,
                id: t.id,
                depth,
                inv_w,
                b_over_w: [b1w0 + b1w_step * i, b2w0 + b2w_step * i],
            });
        };
        if spans {
            // Every pixel of the span passes the three edge tests.
            for x in x0 + xs..x0 + xe {
                fragment(x, i);
                i += 1.0;
            }
        } else {
            for x in x0..x1 {
                if (e[0] | e[1] | e[2]) >= 0 {
                    fragment(x, i);
                }
                for k in 0..3 {
                    e[k] += a[k];
                }
                i += 1.0;
            }
        }
        for k in 0..3 {
            row[k] += b[k];
        }
    }
}

/// Triangle boxes wider than this many pixels are walked by covered spans.
const SPAN_MIN_WIDTH: u32 = 8;

/// The pixel offsets `[start, end)` of a row, within `0..width`, where every edge function
/// `e_k(i) = row[k] + a[k]·i` is ≥ 0: exactly the pixels a test of each one would keep.
#[inline]
fn covered_span(row: &[i64; 3], a: &[i64; 3], width: u32) -> (u32, u32) {
    let (mut lo, mut hi) = (0i64, width as i64); // hi exclusive
    for k in 0..3 {
        let (r, ak) = (row[k], a[k]);
        if ak > 0 {
            // r + ak·i ≥ 0  ⇔  i ≥ ⌈−r / ak⌉
            if r < 0 {
                lo = lo.max((-r + ak - 1) / ak);
            }
        } else if ak < 0 {
            // r + ak·i ≥ 0  ⇔  i ≤ ⌊r / −ak⌋
            if r < 0 {
                return (0, 0);
            }
            hi = hi.min(r / -ak + 1);
        } else if r < 0 {
            return (0, 0);
        }
    }
    if lo >= hi {
        (0, 0)
    } else {
        (lo as u32, hi as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{vec3, Mat4, Vec3};

    use crate::math::TestRng as Lcg;

    /// The span a row walks holds exactly the pixels whose three edge functions are ≥ 0.
    #[test]
    fn covered_spans_equal_a_test_of_every_pixel() {
        let mut rng = Lcg(7);
        let mut pick = |range: i64| (rng.next() as f64 * 2.0 - 1.0) * range as f64;
        for case in 0..20_000 {
            let width = 1 + (case % 97) as u32;
            let scale = [1i64, 256, 1 << 20][case % 3];
            let mut a = [0i64; 3];
            let mut row = [0i64; 3];
            for k in 0..3 {
                a[k] = if case % 11 == k {
                    0
                } else {
                    pick(scale) as i64
                };
                row[k] = pick(scale * width as i64) as i64;
            }
            let brute: Vec<u32> = (0..width)
                .filter(|&i| (0..3).all(|k| row[k] + a[k] * i as i64 >= 0))
                .collect();
            let (lo, hi) = covered_span(&row, &a, width);
            let span: Vec<u32> = (lo..hi).collect();
            assert_eq!(span, brute, "row {row:?} a {a:?} width {width}");
        }
    }

    fn tessellated_quad(rng: &mut Lcg, n: usize) -> Vec<[Vec3; 3]> {
        // A grid of jittered vertices over [-1,1]², split into triangles along random
        // diagonals; the outer boundary stays the square. The jitter (±10% of the spacing)
        // keeps every cell convex, so no triangle folds over a neighbour.
        let mut pts = vec![Vec3::ZERO; (n + 1) * (n + 1)];
        for j in 0..=n {
            for i in 0..=n {
                let mut x = i as f32 / n as f32 * 2.0 - 1.0;
                let mut y = j as f32 / n as f32 * 2.0 - 1.0;
                if i > 0 && i < n {
                    x += (rng.next() - 0.5) * 0.4 / n as f32;
                }
                if j > 0 && j < n {
                    y += (rng.next() - 0.5) * 0.4 / n as f32;
                }
                pts[j * (n + 1) + i] = vec3(x, y, 0.0);
            }
        }
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = pts[j * (n + 1) + i];
                let b = pts[j * (n + 1) + i + 1];
                let c = pts[(j + 1) * (n + 1) + i];
                let d = pts[(j + 1) * (n + 1) + i + 1];
                if rng.next() < 0.5 {
                    tris.push([a, b, d]);
                    tris.push([a, d, c]);
                } else {
                    tris.push([a, b, c]);
                    tris.push([b, d, c]);
                }
            }
        }
        tris
    }

    #[test]
    fn closed_quad_covers_each_pixel_exactly_once() {
        let mut rng = Lcg(7);
        for trial in 0..20 {
            let n = 2 + (trial % 7) * 3;
            let tris = tessellated_quad(&mut rng, n);
            // A random rotation and a perspective view that keeps the whole quad in view.
            let angle = rng.next() * std::f32::consts::TAU;
            let tilt = (rng.next() - 0.5) * 1.2;
            let world = Mat4::from_rotation_z(angle) * Mat4::from_rotation_x(tilt);
            let eye = vec3(0.0, 0.0, 5.0);
            let clip_from_world = crate::math::perspective_rh(0.9, 1.3, 0.1, 100.0)
                * crate::math::look_at_rh(eye, Vec3::ZERO, Vec3::Y);
            let (w, h) = (157, 121);
            let world_tris: Vec<[Vec3; 3]> = tris
                .iter()
                .map(|t| t.map(|p| world.transform_point3(p)))
                .collect();
            let setups = setup(world_tris.len(), w, h, |i| {
                let t = world_tris[i];
                (t.map(|p| clip_from_world * p.extend(1.0)), [0.0; 3])
            });
            let counts = coverage_count(&setups, w, h);
            // Reference coverage: pixel centres strictly inside the projected square.
            let corners: Vec<[f64; 2]> = [
                vec3(-1.0, -1.0, 0.0),
                vec3(1.0, -1.0, 0.0),
                vec3(1.0, 1.0, 0.0),
                vec3(-1.0, 1.0, 0.0),
            ]
            .iter()
            .map(|p| {
                let c = clip_from_world * world.transform_point3(*p).extend(1.0);
                [
                    ((c.x / c.w) as f64 * 0.5 + 0.5) * w as f64,
                    (0.5 - (c.y / c.w) as f64 * 0.5) * h as f64,
                ]
            })
            .collect();
            let mut inside_px = 0;
            for y in 0..h {
                for x in 0..w {
                    let p = [x as f64 + 0.5, y as f64 + 0.5];
                    let mut sgn = [false; 4];
                    let mut dmin = f64::INFINITY;
                    for k in 0..4 {
                        let a = corners[k];
                        let b = corners[(k + 1) % 4];
                        let cr = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
                        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                        dmin = dmin.min((cr / len).abs());
                        sgn[k] = cr > 0.0;
                    }
                    let c = counts[(y * w + x) as usize];
                    assert!(c <= 1, "trial {trial}: pixel {x},{y} covered {c} times");
                    if dmin < 0.01 {
                        continue; // on the outer boundary: either answer is right
                    }
                    let inside = sgn.iter().all(|&s| s) || sgn.iter().all(|&s| !s);
                    assert_eq!(
                        c == 1,
                        inside,
                        "trial {trial}: pixel {x},{y} inside={inside} count={c}"
                    );
                    inside_px += inside as u32;
                }
            }
            assert!(inside_px > 100, "quad too small to test");
        }
    }

    /// A floor quad crossing the near plane and the guard band, split along its diagonal,
    /// set up at 200×200 with each vertex's view depth as its attribute; and the camera's
    /// view and clip matrices.
    fn floor() -> (Vec<SetupTriangle>, Mat4, Mat4) {
        let q = [
            vec3(-50.0, -1.0, 4.9),
            vec3(50.0, -1.0, 4.9),
            vec3(50.0, -1.0, -500.0),
            vec3(-50.0, -1.0, -500.0),
        ];
        let tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let view = crate::math::look_at_rh(vec3(0.0, 0.0, 5.0), vec3(0.0, -0.2, 0.0), Vec3::Y);
        let clip_from_world = crate::math::perspective_rh(1.0, 1.0, 0.1, 1000.0) * view;
        let setups = setup(2, 200, 200, |i| {
            (
                tris[i].map(|p| clip_from_world * p.extend(1.0)),
                tris[i].map(|p| -view.transform_point3(p).z),
            )
        });
        (setups, view, clip_from_world)
    }

    #[test]
    fn clipped_triangles_stay_watertight() {
        let (setups, _, _) = floor();
        let counts = coverage_count(&setups, 200, 200);
        assert!(counts.iter().all(|&c| c <= 1));
        // The floor fills the bottom half of the image with no holes.
        for y in 120..200 {
            for x in 0..200 {
                assert_eq!(counts[y * 200 + x], 1, "hole at {x},{y}");
            }
        }
    }

    /// The depth attribute is interpolated perspective-correctly: on a floor seen in
    /// perspective, each fragment's depth is the view depth where the pixel centre's ray
    /// meets the floor, up to the 1/256-pixel snapping of the vertices.
    #[test]
    fn depths_are_perspective_correct() {
        let (setups, view, clip_from_world) = floor();
        let buf = depth_buffer(&setups, 200, 200);
        let world_from_clip = clip_from_world.inverse().as_dmat4();
        let mut checked = 0;
        for y in 0..200u32 {
            for x in 0..200u32 {
                let d = buf.depth[(y * 200 + x) as usize];
                if !d.is_finite() {
                    continue;
                }
                // The pixel centre's ray, in f64, meets the floor y = −1.
                let ndc = [
                    (x as f64 + 0.5) / 100.0 - 1.0,
                    1.0 - (y as f64 + 0.5) / 100.0,
                ];
                let at = |z: f64| {
                    let p = world_from_clip * glam::DVec4::new(ndc[0], ndc[1], z, 1.0);
                    p.truncate() / p.w
                };
                let (a, b) = (at(0.2), at(0.8));
                let hit = a + (b - a) * ((-1.0 - a.y) / (b.y - a.y));
                let exact = -view.as_dmat4().transform_point3(hit).z;
                if exact > 50.0 {
                    // Towards the horizon the depth changes too fast per pixel for the
                    // snapping's 1/512 pixel to stay within the tolerance.
                    continue;
                }
                // Nearer, depth changes by at most half of itself per pixel.
                assert!(
                    (d as f64 - exact).abs() <= 1e-3 * exact,
                    "{x},{y}: {d} against {exact}"
                );
                checked += 1;
            }
        }
        assert!(checked > 10_000, "{checked}");
    }
}
