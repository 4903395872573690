//! The transformation of samples for a directional light, computed for blocks of samples at
//! once: every lit sample's shadow ray shares the light's direction (so its watertight
//! shear is formed once a frame), and the per-sample arithmetic — the origin offset by the
//! position's error bound, rounded away from the surface, and the orthographic projection —
//! runs on arrays of coordinates in operations that vectorize, with an AVX2 variant chosen
//! at run time (eight samples a step, the same operations and no fused multiply-adds, so
//! the same bits as the scalar path of [`SurfacePoint::offset_origin`] and
//! [`Ortho::coords`]).

use super::super::shadow_ray::ShadowRay;
use super::{Ortho, Pt};
use crate::math::{RayShear, Vec3};
use crate::raster::NO_TRIANGLE;
use crate::view::ViewSamples;

/// Samples per step of the block arithmetic.
const LANES: usize = 64;

/// What every sample of a directional light's frame shares.
pub(in super::super) struct Directional<'a> {
    pub(in super::super) view: &'a ViewSamples,
    /// The light's `to_light` vector, as [`crate::light::Light::shadow_ray`] returns it.
    pub(in super::super) to_light: Vec3,
    pub(in super::super) shear: RayShear,
    pub(in super::super) ortho: Ortho,
}

impl Directional<'_> {
    /// True when pixel `k` shows a surface the light reaches if nothing is in the way: the
    /// test of [`crate::frame::Frame::receiver_lit`] for a directional light, whose shadow
    /// rays are infinite and which has no cone (a NaN product counts as lit there too).
    #[inline]
    pub(in super::super) fn lit(&self, k: usize) -> bool {
        let facing = self.view.normal[k].dot(self.to_light);
        self.view.triangle[k] != NO_TRIANGLE && (facing > 0.0 || facing.is_nan())
    }

    /// The shadow rays and points of the lit pixels among `pixels`, into `rays` and `pts`
    /// (which hold exactly that many), their ids counted from `first`.
    pub(in super::super) fn block(
        &self,
        pixels: std::ops::Range<usize>,
        first: usize,
        rays: &mut [ShadowRay],
        pts: &mut [Pt],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            #[allow(unsafe_code)]
            unsafe {
                self.block_avx2(pixels, first, rays, pts)
            };
            return;
        }
        self.block_body(pixels, first, rays, pts);
    }

    /// [`Self::block`] compiled for AVX2: the same operations eight lanes wide.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn block_avx2(
        &self,
        pixels: std::ops::Range<usize>,
        first: usize,
        rays: &mut [ShadowRay],
        pts: &mut [Pt],
    ) {
        self.block_body(pixels, first, rays, pts);
    }

    /// The body of [`Self::block`], inlined into each instruction-set variant.
    #[inline(always)]
    fn block_body(
        &self,
        pixels: std::ops::Range<usize>,
        first: usize,
        rays: &mut [ShadowRay],
        pts: &mut [Pt],
    ) {
        let view = self.view;
        let mut lanes = Lanes::default();
        let mut j = 0;
        let mut k = pixels.start;
        while k < pixels.end {
            // Gather up to LANES lit samples.
            let mut m = 0;
            while k < pixels.end && m < LANES {
                if self.lit(k) {
                    lanes.load(m, k, view);
                    m += 1;
                }
                k += 1;
            }
            lanes.offset_origins(self.to_light);
            lanes.project(&self.ortho);
            for i in 0..m {
                let o = Vec3::new(lanes.o[0][i], lanes.o[1][i], lanes.o[2][i]);
                let pixel = lanes.pixel[i];
                let own = view.triangle[pixel as usize];
                rays[j] = ShadowRay::sheared(o, self.shear, f32::INFINITY, own, pixel);
                pts[j] = Pt {
                    u: lanes.uvz[0][i],
                    v: lanes.uvz[1][i],
                    z: lanes.uvz[2][i],
                    id: (first + j) as u32,
                };
                j += 1;
            }
        }
    }
}

/// One step's samples, a coordinate array per axis. Lanes past the step's count keep
/// finite values of an earlier step (or zeros) and are never stored.
struct Lanes {
    pixel: [u32; LANES],
    p: [[f32; LANES]; 3],
    e: [[f32; LANES]; 3],
    n: [[f32; LANES]; 3],
    o: [[f32; LANES]; 3],
    uvz: [[f32; LANES]; 3],
}

impl Default for Lanes {
    fn default() -> Self {
        Lanes {
            pixel: [0; LANES],
            p: [[0.0; LANES]; 3],
            e: [[0.0; LANES]; 3],
            n: [[0.0; LANES]; 3],
            o: [[0.0; LANES]; 3],
            uvz: [[0.0; LANES]; 3],
        }
    }
}

impl Lanes {
    /// Pixel `k`'s position, error bound and normal into lane `i`.
    #[inline(always)]
    fn load(&mut self, i: usize, k: usize, view: &ViewSamples) {
        let (p, e, n) = (view.position[k], view.position_error[k], view.normal[k]);
        for a in 0..3 {
            self.p[a][i] = p[a];
            self.e[a][i] = e[a];
            self.n[a][i] = n[a];
        }
        self.pixel[i] = k as u32;
    }

    /// [`crate::math::SurfacePoint::offset_origin`] of every lane towards `w`, operation
    /// for operation.
    #[inline(always)]
    fn offset_origins(&mut self, w: Vec3) {
        let [px, py, pz] = &self.p;
        let [ex, ey, ez] = &self.e;
        let [nx, ny, nz] = &self.n;
        let [ox, oy, oz] = &mut self.o;
        for i in 0..LANES {
            let d = (nx[i].abs() * ex[i]) + (ny[i].abs() * ey[i]) + (nz[i].abs() * ez[i]);
            let flip = ((w.x * nx[i]) + (w.y * ny[i]) + (w.z * nz[i])) < 0.0;
            let (mut fx, mut fy, mut fz) = (nx[i] * d, ny[i] * d, nz[i] * d);
            if flip {
                (fx, fy, fz) = (-fx, -fy, -fz);
            }
            ox[i] = away(px[i] + fx, fx);
            oy[i] = away(py[i] + fy, fy);
            oz[i] = away(pz[i] + fz, fz);
        }
    }

    /// [`Ortho::coords`] of every lane's origin.
    #[inline(always)]
    fn project(&mut self, ortho: &Ortho) {
        let [ox, oy, oz] = &self.o;
        let [u, v, z] = &mut self.uvz;
        let (c, s, t, w) = (ortho.c, ortho.s, ortho.t, ortho.w);
        for i in 0..LANES {
            let (qx, qy, qz) = (ox[i] - c.x, oy[i] - c.y, oz[i] - c.z);
            u[i] = (qx * s.x) + (qy * s.y) + (qz * s.z);
            v[i] = (qx * t.x) + (qy * t.y) + (qz * t.z);
            z[i] = (qx * w.x) + (qy * w.y) + (qz * w.z);
        }
    }
}

/// `x` moved one step away from the surface in the direction of `offset`: `x.next_up()`
/// for a positive offset, `x.next_down()` for a negative one, `x` itself for zero (or a
/// NaN offset), computed on the bits without branches so it vectorizes.
#[inline(always)]
fn away(x: f32, offset: f32) -> f32 {
    const SIGN: u32 = 0x8000_0000;
    let bits = x.to_bits();
    let abs = bits & !SIGN;
    let up = offset > 0.0;
    let down = offset < 0.0;
    // next_up: +0/−0 → smallest positive; positive → bits + 1; negative → bits − 1.
    // next_down: +0/−0 → smallest negative; positive → bits − 1; negative → bits + 1.
    let positive = bits == abs;
    let grow = (up && positive) || (down && !positive);
    let stepped = if abs == 0 {
        if up {
            1
        } else {
            SIGN | 1
        }
    } else if grow {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    };
    // NaN stays; +∞ stays under next_up, −∞ under next_down.
    let keep = x.is_nan()
        || (up && bits == f32::INFINITY.to_bits())
        || (down && bits == f32::NEG_INFINITY.to_bits())
        || !(up || down);
    if keep {
        x
    } else {
        f32::from_bits(stepped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::TestRng as Lcg;

    fn scalar(x: f32, offset: f32) -> f32 {
        if offset > 0.0 {
            x.next_up()
        } else if offset < 0.0 {
            x.next_down()
        } else {
            x
        }
    }

    /// Each lit sample of a real view through the block path (the dispatched variant and
    /// the plain body) against the scalar formulas, bit for bit.
    #[test]
    fn block_equals_the_per_sample_transform() {
        use crate::light::{pick_up, Light};
        use crate::math::SurfacePoint;
        let scene = crate::scene::load("chessboard", &Default::default()).unwrap();
        let mut camera = scene.camera.unwrap();
        (camera.width, camera.height) = (160, 120);
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let to_light = Vec3::new(-0.3, 0.8, 0.5);
        let light = Light::Directional { to_light };
        let w = -to_light.normalize();
        let s = w.cross(pick_up(w)).normalize();
        let ortho = Ortho {
            c: scene.bounds.center(),
            s,
            t: s.cross(w),
            w,
        };
        let d = Directional {
            view: &view,
            to_light,
            shear: RayShear::new(to_light),
            ortho,
        };
        let n = view.triangle.len();
        let lit: Vec<usize> = (0..n).filter(|&k| d.lit(k)).collect();
        let frame = crate::frame::Frame::new(&scene, &camera, &light, &view);
        assert!(lit.len() > n / 4);
        assert_eq!(
            lit,
            (0..n)
                .filter(|&k| frame.receiver_lit(k))
                .collect::<Vec<_>>()
        );
        let placeholder = ShadowRay::new(Vec3::ZERO, Vec3::Z, 0.0, 0, 0);
        let origin = Pt {
            u: 0.0,
            v: 0.0,
            z: 0.0,
            id: 0,
        };
        let run = |plain: bool| {
            let (mut rays, mut pts) = (vec![placeholder; lit.len()], vec![origin; lit.len()]);
            if plain {
                d.block_body(0..n, 3, &mut rays, &mut pts);
            } else {
                d.block(0..n, 3, &mut rays, &mut pts);
            }
            (rays, pts)
        };
        for (rays, pts) in [run(true), run(false)] {
            for (j, &k) in lit.iter().enumerate() {
                let sp = SurfacePoint {
                    p: view.position[k],
                    error: view.position_error[k],
                };
                let o = sp.offset_origin(view.normal[k], to_light);
                let [u, v, z] = ortho.coords(o);
                let bits = |a: [f32; 3]| a.map(f32::to_bits);
                assert_eq!(bits(rays[j].o), bits(o.to_array()), "pixel {k}");
                assert_eq!((rays[j].own, rays[j].pixel), (view.triangle[k], k as u32));
                assert_eq!(bits([pts[j].u, pts[j].v, pts[j].z]), bits([u, v, z]));
                assert_eq!(pts[j].id, (3 + j) as u32);
            }
        }
    }

    #[test]
    fn away_is_next_up_or_next_down() {
        let special = [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0,
            -1.0,
        ];
        let offsets = [1.0, -1.0, 0.0, -0.0, f32::NAN];
        for &x in &special {
            for &o in &offsets {
                assert_eq!(away(x, o).to_bits(), scalar(x, o).to_bits(), "{x} {o}");
            }
        }
        let mut rng = Lcg(5);
        for _ in 0..100_000 {
            let half = |r: &mut Lcg| (r.next() * 65536.0) as u32 & 0xffff;
            let x = f32::from_bits((half(&mut rng) << 16) | half(&mut rng));
            let o = rng.next() - 0.5;
            assert_eq!(away(x, o).to_bits(), scalar(x, o).to_bits(), "{x} {o}");
        }
    }
}
