//! Faces a file lists more than once.
//!
//! Exported and scanned meshes sometimes repeat a face exactly, and a hostile file can
//! repeat one face millions of times: every copy covers the same pixels and texels, so the
//! copies multiply the work of every technique and of every ray that meets them while
//! changing no answer. A face that repeats, vertex for vertex and bit for bit, an earlier
//! *opaque* face is therefore dropped when a file is loaded: a ray or texel that meets the
//! copy meets the earlier face at the same depth, and the camera pass's ties already go to
//! the lower index, so no pixel of any technique or of the reference changes. Repeats of a
//! semi-transparent or alpha-masked face stay, since each copy filters the light again (or
//! may carry other texture coordinates). The materials that only dropped copies used go
//! with them, so a file of 600,000 copies of one shape leaves one shape and one material,
//! not a material list that every later pass walks.

use super::Scene;

impl Scene {
    /// Drops every triangle whose three vertices equal (bit for bit, in the same order)
    /// those of an earlier triangle with an opaque material, and returns how many were
    /// dropped. Triangle order, materials and mesh ranges are kept; bounds are unchanged
    /// (every dropped vertex is also an earlier triangle's).
    pub fn drop_repeated_faces(&mut self) -> usize {
        let n = self.len();
        let bits = |i: usize| -> [u32; 9] {
            let (a, b, c) = (self.v0[i], self.v1[i], self.v2[i]);
            [a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z].map(f32::to_bits)
        };
        let mut keys: Vec<(u64, u32)> = (0..n)
            .map(|i| {
                let h = bits(i).iter().fold(0x9e37_79b9_7f4a_7c15u64, |h, &v| {
                    (h ^ u64::from(v))
                        .wrapping_mul(0xff51_afd7_ed55_8ccd)
                        .rotate_left(29)
                });
                (h, i as u32)
            })
            .collect();
        keys.sort_unstable();
        let mut drop = vec![false; n];
        let mut dropped = 0;
        // Within a run of equal hashes (in index order), each triangle is compared with
        // the distinct opaque faces met before it in the run.
        let mut earlier: Vec<usize> = Vec::new();
        for run in keys.chunk_by(|a, b| a.0 == b.0) {
            earlier.clear();
            for &(_, i) in run {
                let i = i as usize;
                let v = bits(i);
                if earlier.iter().any(|&e| bits(e) == v) {
                    drop[i] = true;
                    dropped += 1;
                } else if self.material_of(i).is_opaque()
                    && self.material_of(i).alpha_mask.is_none()
                {
                    earlier.push(i);
                }
            }
        }
        if dropped == 0 {
            return 0;
        }
        let mut kept_before = 0;
        let mut ends = self.mesh_ends.iter_mut().peekable();
        let mut w = 0;
        for (r, &gone) in drop.iter().enumerate() {
            while let Some(end) = ends.next_if(|e| **e == r) {
                *end = kept_before;
            }
            if gone {
                continue;
            }
            self.v0[w] = self.v0[r];
            self.v1[w] = self.v1[r];
            self.v2[w] = self.v2[r];
            self.material[w] = self.material[r];
            if !self.uv.is_empty() {
                self.uv[w] = self.uv[r];
            }
            w += 1;
            kept_before += 1;
        }
        for end in ends {
            *end = kept_before;
        }
        self.v0.truncate(w);
        self.v1.truncate(w);
        self.v2.truncate(w);
        self.material.truncate(w);
        self.uv.truncate(w);
        self.drop_unused_materials();
        dropped
    }

    /// Drops the materials no triangle uses, keeping the others in order.
    fn drop_unused_materials(&mut self) {
        let mut used = vec![false; self.materials.len()];
        for &m in &self.material {
            used[m as usize] = true;
        }
        if used.iter().all(|&u| u) {
            return;
        }
        let mut new_index = vec![0u32; used.len()];
        let mut next = 0u32;
        for (i, &u) in used.iter().enumerate() {
            new_index[i] = next;
            next += u32::from(u);
        }
        let mut i = 0;
        self.materials.retain(|_| {
            i += 1;
            used[i - 1]
        });
        for m in &mut self.material {
            *m = new_index[*m as usize];
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::math::vec3;
    use crate::scene::{Material, Scene};

    #[test]
    fn repeats_of_opaque_faces_go_and_repeats_of_translucent_ones_stay() {
        let mut s = Scene::new("t");
        let opaque = s.add_material(Material::opaque("o", vec3(1.0, 1.0, 1.0)));
        let mut glass = Material::opaque("g", vec3(1.0, 1.0, 1.0));
        glass.transmittance = vec3(0.5, 0.5, 0.5);
        let glass = s.add_material(glass);
        let a = [
            vec3(0.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
            vec3(0.0, 1.0, 0.0),
        ];
        let b = [a[1], a[2], a[0]]; // the same face, another first vertex: kept
        let c = [
            vec3(0.0, 0.0, 1.0),
            vec3(1.0, 0.0, 1.0),
            vec3(0.0, 1.0, 1.0),
        ];
        for (t, m) in [
            (a, opaque),
            (a, opaque),
            (b, opaque),
            (c, glass),
            (a, glass),
            (c, glass),
            (a, opaque),
        ] {
            s.push(t, m);
        }
        s.mesh_ends = vec![2, 4, 7];
        assert_eq!(s.drop_repeated_faces(), 3);
        assert_eq!(s.len(), 4);
        assert_eq!(s.v0, vec![a[0], b[0], c[0], c[0]]);
        assert_eq!(s.material, vec![opaque, opaque, glass, glass]);
        assert_eq!(s.mesh_ends, vec![1, 3, 4]);
        assert_eq!(s.drop_repeated_faces(), 0);
    }
}
