//! The paper's frustum culling (Fernando et al. 2001, Section 4.3) for the pages: "since it
//! is inefficient to redraw the whole scene for each grid cell during refinement", each
//! page of the coarsest level (a cell) lists the triangles whose projection overlaps it,
//! and every page of a finer level, which lies inside one cell, is drawn from that cell's
//! list alone. The lists are made once per virtual map, on the CPU, and uploaded.

use super::pool::{Layout, Page};
use rayon::prelude::*;
use shadowlab::light::LightView;
use shadowlab::scene::Scene;
use shadowlab::techniques::adaptive::clipped_uv_bounds;

/// Every cell's triangles, concatenated: cell `c`'s are `triangles[first[c]..first[c + 1]]`.
pub(super) struct Culling {
    pub(super) first: Vec<u32>,
    pub(super) triangles: Vec<u32>,
}

impl Culling {
    /// Lists the triangles of `scene` per cell of every view's coarsest level.
    pub(super) fn new(scene: &Scene, views: &[LightView], layout: &Layout) -> Self {
        let n = layout.pages_across(layout.levels - 1) as usize;
        // One texel of the finest level: f32 rounding never leaves a triangle out.
        let margin = 1.0 / layout.side as f32;
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); views.len() * n * n];
        for (f, v) in views.iter().enumerate() {
            let ranges: Vec<Option<[usize; 4]>> = (0..scene.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|t| {
                    let c = scene.triangle(t).map(|p| v.clip_from_world * p.extend(1.0));
                    let [u0, v0, u1, v1] = clipped_uv_bounds(c)?;
                    if !(u1 >= -margin && v1 >= -margin && u0 <= 1.0 + margin && v0 <= 1.0 + margin)
                    {
                        return None;
                    }
                    let cell = |x: f32| ((x * n as f32).floor() as i64).clamp(0, n as i64 - 1);
                    Some(
                        [u0 - margin, v0 - margin, u1 + margin, v1 + margin]
                            .map(|x| cell(x) as usize),
                    )
                })
                .collect();
            for (t, r) in ranges.into_iter().enumerate() {
                if let Some([x0, y0, x1, y1]) = r {
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            bins[(f * n + y) * n + x].push(t as u32);
                        }
                    }
                }
            }
        }
        let mut first = Vec::with_capacity(bins.len() + 1);
        let mut triangles = Vec::new();
        for b in bins {
            first.push(triangles.len() as u32);
            triangles.extend(b);
        }
        first.push(triangles.len() as u32);
        Culling { first, triangles }
    }

    /// The cell holding `page`, and the range of its triangles.
    pub(super) fn of(&self, layout: &Layout, page: Page) -> (u32, u32) {
        let shift = layout.levels - 1 - page.level;
        let n = layout.pages_across(layout.levels - 1);
        let c = ((page.face * n + (page.y >> shift)) * n + (page.x >> shift)) as usize;
        (self.first[c], self.first[c + 1] - self.first[c])
    }

    /// Bytes of the lists.
    pub(super) fn bytes(&self) -> u64 {
        4 * (self.first.len() + self.triangles.len()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab::light::light_views;
    use shadowlab::math::ndc_to_uv;
    use shadowlab::techniques::shadow_map::DIRECTIONAL_PAD;

    /// Every vertex of every triangle in front of the light lies in a cell that lists the
    /// triangle, and a cell lists only triangles whose projection reaches near it.
    #[test]
    fn each_cell_lists_the_triangles_over_it() {
        let scene = shadowlab::scene::load("bunny", &Default::default()).unwrap();
        let light = scene.light.unwrap();
        let views = light_views(&light, &scene.bounds, &scene.bounds, DIRECTIONAL_PAD);
        let layout = Layout {
            page: 32,
            levels: 3,
            side: 512 << 2,
            faces: views.len() as u32,
        };
        let c = Culling::new(&scene, &views, &layout);
        let n = layout.pages_across(2);
        let listed = |cell: u32, t: u32| {
            let (a, b) = (c.first[cell as usize], c.first[cell as usize + 1]);
            c.triangles[a as usize..b as usize].contains(&t)
        };
        for t in 0..scene.len() {
            for p in scene.triangle(t) {
                let q = views[0].clip_from_world * p.extend(1.0);
                let (u, v) = ndc_to_uv(q);
                if !(q.w > 0.0 && (0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)) {
                    continue;
                }
                let cell = (v * n as f32) as u32 * n + (u * n as f32) as u32;
                assert!(
                    listed(cell, t as u32),
                    "triangle {t} missing from cell {cell}"
                );
            }
        }
        // Culling culls: the lists together hold far fewer than every triangle per cell.
        assert!(c.triangles.len() < scene.len() * (n * n) as usize / 8);
    }
}
