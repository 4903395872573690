//! Area lights — a rectangle, a disk, a sphere, or a sun of some angular size — and the
//! fixed set of light samples that the soft-shadow reference and the exact soft technique
//! share.
//!
//! The shadow term under an area light is the fraction of its emitting area that a point
//! sees (each sample weighted by the RGB transmittance towards it): a pure visibility, not
//! irradiance, so that it stays in `[0, 1]` and is comparable with the hard shadow term.
//! A sample counts only when it lies on the viewed side of the point's surface; a point
//! that a sized spot light's cone (from its centre) leaves out is unlit, as under the
//! punctual spot.
//!
//! Invariants:
//! - Rectangles and disks emit from both faces (like the point light at their centre
//!   that hard techniques see).
//! - A sphere is seen from each point as its cross-section facing the point (the disk
//!   through its centre perpendicular to the direction towards the point): its samples
//!   move with the point, every other shape's samples are the same for every point.
//! - The samples are the first `n` points of the base-2 (0,2)-sequence (Sobol's first two
//!   dimensions) mapped to the shape by area-preserving maps: every power-of-two prefix
//!   and every aligned power-of-two block has exactly one point in each elementary
//!   interval of the unit square, so they are stratified and of low discrepancy, and a
//!   pixel's supersampled primary rays can each take one aligned block.
//!
//! Map-based (hard) techniques see the light's centre as a punctual light
//! ([`AreaLight::punctual`]).

use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::{vec2, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// The most light samples the reference and the soft techniques take per point.
pub const MAX_LIGHT_SAMPLES: u32 = 65536;

/// The default number of light samples per pixel.
pub const DEFAULT_LIGHT_SAMPLES: u32 = 256;

/// A light with an emitting area.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum AreaLight {
    /// A parallelogram `centre + s·edge_u + t·edge_v`, `s, t ∈ [-½, ½]` (a rectangle when
    /// the edges are perpendicular).
    Rect {
        /// Centre.
        centre: Vec3,
        /// First edge vector (its full length).
        edge_u: Vec3,
        /// Second edge vector.
        edge_v: Vec3,
    },
    /// A disk of `radius` about `centre`, perpendicular to `normal`.
    Disk {
        /// Centre.
        centre: Vec3,
        /// Unit normal.
        normal: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A sphere of `radius` about `centre`.
    Sphere {
        /// Centre.
        centre: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A light at infinity seen as a disk of angular diameter `angle_deg` about
    /// `to_light` (a directional light given a size: the sun is about 0.53°).
    Distant {
        /// Unit vector towards the light's centre.
        to_light: Vec3,
        /// Angular diameter in degrees.
        angle_deg: f32,
    },
}

/// One light sample as seen from a point: the unit direction towards it and its distance
/// (infinite for a distant light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPoint {
    /// Unit direction from the point towards the sample.
    pub dir: Vec3,
    /// Distance to the sample.
    pub dist: f32,
}

impl AreaLight {
    /// The area light a punctual light becomes when given a size: a point light a sphere
    /// of radius `size`, a spot light a disk of radius `size` facing its target (keeping
    /// its cone), a directional light a distant disk of angular diameter `size` degrees.
    pub fn sized(light: &Light, size: f32) -> Result<AreaLight> {
        let a = match *light {
            Light::Point { position } => AreaLight::Sphere {
                centre: position,
                radius: size,
            },
            Light::Spot {
                position, target, ..
            } => AreaLight::Disk {
                centre: position,
                normal: (target - position).normalize(),
                radius: size,
            },
            Light::Directional { to_light } => AreaLight::Distant {
                to_light: to_light.normalize(),
                angle_deg: size,
            },
        };
        a.validate()?;
        Ok(a)
    }

    /// Checks for non-finite values, empty areas and impossible angles.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &str| Err(Error::param(what.to_string()));
        match *self {
            AreaLight::Rect {
                centre,
                edge_u,
                edge_v,
            } => {
                if !(centre.is_finite() && edge_u.is_finite() && edge_v.is_finite()) {
                    return bad("rect light centre and edges must be finite");
                }
                let area = edge_u.cross(edge_v).length();
                if !(area.is_finite() && area > 0.0) {
                    return bad("rect light edges must be non-zero and not parallel");
                }
            }
            AreaLight::Disk {
                centre,
                normal,
                radius,
            } => {
                if !(centre.is_finite() && normal.is_finite()) {
                    return bad("disk light centre and normal must be finite");
                }
                let n2 = normal.length_squared();
                if !(n2.is_finite() && n2 > 1e-12) {
                    return bad("disk light normal must be a non-zero vector");
                }
                if !(radius.is_finite() && radius > 0.0) {
                    return bad("disk light radius must be a positive number");
                }
            }
            AreaLight::Sphere { centre, radius } => {
                if !centre.is_finite() {
                    return bad("sphere light centre must be finite");
                }
                if !(radius.is_finite() && radius > 0.0) {
                    return bad("sphere light radius must be a positive number");
                }
            }
            AreaLight::Distant {
                to_light,
                angle_deg,
            } => {
                let len2 = to_light.length_squared();
                if !(to_light.is_finite() && len2.is_finite() && len2 > 1e-12) {
                    return bad("distant light direction must be a finite, non-zero vector");
                }
                if !(angle_deg > 0.0 && angle_deg < 90.0) {
                    return Err(Error::param(format!(
                        "distant light angular diameter {angle_deg}° is outside (0°, 90°)"
                    )));
                }
            }
        }
        Ok(())
    }

    /// The light with its normal or direction of unit length.
    pub fn normalized(self) -> AreaLight {
        match self {
            AreaLight::Disk {
                centre,
                normal,
                radius,
            } => AreaLight::Disk {
                centre,
                normal: normal.normalize(),
                radius,
            },
            AreaLight::Distant {
                to_light,
                angle_deg,
            } => AreaLight::Distant {
                to_light: to_light.normalize(),
                angle_deg,
            },
            a => a,
        }
    }

    /// The punctual light at the centre that hard techniques see: a point light, or a
    /// directional one for a distant light.
    pub fn punctual(&self) -> Light {
        match *self {
            AreaLight::Rect { centre, .. }
            | AreaLight::Disk { centre, .. }
            | AreaLight::Sphere { centre, .. } => Light::Point { position: centre },
            AreaLight::Distant { to_light, .. } => Light::Directional { to_light },
        }
    }

    /// A short name: `rect`, `disk`, `sphere` or `distant`.
    pub fn kind(&self) -> &'static str {
        match self {
            AreaLight::Rect { .. } => "rect",
            AreaLight::Disk { .. } => "disk",
            AreaLight::Sphere { .. } => "sphere",
            AreaLight::Distant { .. } => "distant",
        }
    }

    /// The largest extent of the light: the rectangle's half diagonal, the radius, or for
    /// a distant light the tangent of its angular radius (its extent at unit distance).
    pub fn radius(&self) -> f32 {
        match *self {
            AreaLight::Rect { edge_u, edge_v, .. } => {
                0.5 * (edge_u + edge_v).length().max((edge_u - edge_v).length())
            }
            AreaLight::Disk { radius, .. } | AreaLight::Sphere { radius, .. } => radius,
            AreaLight::Distant { angle_deg, .. } => (angle_deg.to_radians() * 0.5).tan(),
        }
    }

    /// The side of the square of equal area (what Fernando's `LIGHT_WORLD_SIZE` means): for
    /// a distant light, its angular width in radians (the side at unit distance).
    pub fn equivalent_width(&self) -> f32 {
        match *self {
            AreaLight::Rect { edge_u, edge_v, .. } => edge_u.cross(edge_v).length().sqrt(),
            AreaLight::Disk { radius, .. } | AreaLight::Sphere { radius, .. } => {
                radius * std::f32::consts::PI.sqrt()
            }
            AreaLight::Distant { .. } => self.radius() * std::f32::consts::PI.sqrt(),
        }
    }

    /// True when the samples are the same world points (or directions) for every
    /// receiver: every shape but the sphere.
    pub fn fixed_samples(&self) -> bool {
        !matches!(self, AreaLight::Sphere { .. })
    }

    /// The sample at `uv ∈ [0, 1)²` seen from `p`: for a distant light a direction (its
    /// distance infinite), else a point on the shape.
    pub fn sample_from(&self, p: Vec3, uv: Vec2) -> LightPoint {
        match *self {
            AreaLight::Distant { to_light, .. } => {
                let (a, b) = orthonormal_basis(to_light);
                let d = concentric_disk(uv) * self.radius();
                LightPoint {
                    dir: (to_light + a * d.x + b * d.y).normalize(),
                    dist: f32::INFINITY,
                }
            }
            _ => {
                let s = self.position(p, uv) - p;
                let dist = s.length();
                LightPoint {
                    dir: s / dist,
                    dist,
                }
            }
        }
    }

    /// The world point of the sample at `uv` seen from `p` (for a distant light, a point
    /// at unit distance from `p`).
    pub fn position(&self, p: Vec3, uv: Vec2) -> Vec3 {
        match *self {
            AreaLight::Rect {
                centre,
                edge_u,
                edge_v,
            } => centre + edge_u * (uv.x - 0.5) + edge_v * (uv.y - 0.5),
            AreaLight::Disk {
                centre,
                normal,
                radius,
            } => {
                let (a, b) = orthonormal_basis(normal);
                let d = concentric_disk(uv) * radius;
                centre + a * d.x + b * d.y
            }
            AreaLight::Sphere { centre, radius } => {
                let w = (p - centre).normalize_or_zero();
                let w = if w == Vec3::ZERO { Vec3::Y } else { w };
                let (a, b) = orthonormal_basis(w);
                let d = concentric_disk(uv) * radius;
                centre + a * d.x + b * d.y
            }
            AreaLight::Distant { .. } => p + self.sample_from(p, uv).dir,
        }
    }

    /// True when a receiver at `p` can be lit at all by a light that `stand_in` (the
    /// punctual light the area light came from) restricts: outside a spot's cone it is not.
    pub fn in_cone(stand_in: &Light, p: Vec3) -> bool {
        stand_in.cone_contains(stand_in.shadow_ray(p).0)
    }
}

/// Checks a light sample count: 1 to [`MAX_LIGHT_SAMPLES`].
pub fn check_light_samples(n: u32) -> Result<()> {
    if n == 0 || n > MAX_LIGHT_SAMPLES {
        return Err(Error::param(format!(
            "light samples {n} is outside 1..={MAX_LIGHT_SAMPLES}"
        )));
    }
    Ok(())
}

/// The first `n` points of the base-2 (0,2)-sequence: the van der Corput radical inverse
/// and Sobol's second dimension. The `k`-th point is the same whatever `n`, so a reference
/// with twice the samples holds the first one's samples.
pub fn light_samples(n: u32) -> Vec<Vec2> {
    (0..n).map(sobol_point).collect()
}

/// The `i`-th point of the (0,2)-sequence in `[0, 1)²`.
pub fn sobol_point(i: u32) -> Vec2 {
    let x = i.reverse_bits();
    let mut y = 0u32;
    let mut v = 1u32 << 31;
    let mut k = i;
    while k != 0 {
        if k & 1 != 0 {
            y ^= v;
        }
        k >>= 1;
        v ^= v >> 1;
    }
    let scale = 1.0 / 4294967296.0;
    vec2((x as f64 * scale) as f32, (y as f64 * scale) as f32)
}

/// Shirley and Chiu's concentric map of the unit square onto the unit disk: area
/// preserving, and it keeps the square's strata compact.
pub(crate) fn concentric_disk(uv: Vec2) -> Vec2 {
    let o = uv * 2.0 - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, quarter * (o.y / o.x))
    } else {
        (o.y, 2.0 * quarter - quarter * (o.x / o.y))
    };
    vec2(theta.cos(), theta.sin()) * r
}

/// Two unit vectors perpendicular to the unit vector `n` and to each other (Duff et al.
/// 2017: branchless, continuous away from `n.z = -1`).
pub(crate) fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::vec3;

    #[test]
    fn power_of_two_prefixes_are_stratified() {
        for m in 0..=10u32 {
            let n = 1u32 << m;
            let pts = light_samples(n);
            // Every elementary interval of area 1/n: 2^a columns by 2^(m-a) rows.
            for a in 0..=m {
                let (cols, rows) = (1u32 << a, 1u32 << (m - a));
                let mut seen = vec![false; n as usize];
                for p in &pts {
                    let c = (p.x * cols as f32) as u32;
                    let r = (p.y * rows as f32) as u32;
                    let cell = (r * cols + c) as usize;
                    assert!(!seen[cell], "n={n} {cols}x{rows} cell {cell} twice");
                    seen[cell] = true;
                }
            }
        }
    }

    #[test]
    fn samples_lie_on_their_shapes() {
        let rect = AreaLight::Rect {
            centre: vec3(0.0, 4.0, 0.0),
            edge_u: vec3(2.0, 0.0, 0.0),
            edge_v: vec3(0.0, 0.0, 1.0),
        };
        let disk = AreaLight::Disk {
            centre: vec3(1.0, 3.0, 0.0),
            normal: vec3(0.0, -1.0, 0.0),
            radius: 0.5,
        };
        let sphere = AreaLight::Sphere {
            centre: vec3(0.0, 5.0, 0.0),
            radius: 0.7,
        };
        let p = vec3(0.3, 0.0, -0.2);
        for uv in light_samples(64) {
            let s = rect.position(p, uv);
            assert!((s.y - 4.0).abs() < 1e-6 && s.x.abs() <= 1.0 && s.z.abs() <= 0.5);
            let s = disk.position(p, uv);
            assert!((s.y - 3.0).abs() < 1e-6 && (s - vec3(1.0, 3.0, 0.0)).length() <= 0.5001);
            let s = sphere.position(p, uv);
            let c = vec3(0.0, 5.0, 0.0);
            assert!((s - c).length() <= 0.7001);
            assert!(
                (s - c).dot(p - c).abs() < 1e-4,
                "in the cross-section facing p"
            );
        }
    }
}
