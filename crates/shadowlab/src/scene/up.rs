//! The up axis of a mesh file: which of the file's axes points up. shadowlab's world is
//! Y-up; a file written Z-up (as SketchUp, 3ds Max, CAD tools and many scanners write
//! them) is turned on loading so that its up axis becomes +Y.
//!
//! Every turn is a proper rotation (no mirror) by a right angle or two, about the X axis
//! for the file's ±Y and ±Z and about the Z axis for its ±X:
//!
//! | up | a file point (x, y, z) lands at |
//! |---|---|
//! | `y` | (x, y, z) |
//! | `z` | (x, z, −y) |
//! | `-z` | (x, −z, y) |
//! | `-y` | (x, −y, −z) |
//! | `x` | (−y, x, z) |
//! | `-x` | (y, −x, z) |
//!
//! A coordinate is only moved and negated, never multiplied, so a turned file holds the
//! very numbers its Y-up twin holds.

use super::Scene;
use crate::area_light::AreaLight;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The axis of a file that points up; serialized as its name (`"z"`, `"-x"`, …).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum UpAxis {
    /// +X up.
    #[serde(rename = "x")]
    X,
    /// +Y up: shadowlab's own convention, nothing turns.
    #[default]
    #[serde(rename = "y")]
    Y,
    /// +Z up.
    #[serde(rename = "z")]
    Z,
    /// −X up.
    #[serde(rename = "-x")]
    NegX,
    /// −Y up.
    #[serde(rename = "-y")]
    NegY,
    /// −Z up.
    #[serde(rename = "-z")]
    NegZ,
}

impl UpAxis {
    /// Every axis, as the command line spells them.
    pub const NAMES: &'static str = "x, y, z, -x, -y or -z";

    /// The name the command line and the records use: `x`, `y`, `z`, `-x`, `-y`, `-z`.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::X => "x",
            UpAxis::Y => "y",
            UpAxis::Z => "z",
            UpAxis::NegX => "-x",
            UpAxis::NegY => "-y",
            UpAxis::NegZ => "-z",
        }
    }

    /// Where the file's point (or direction) `p` lands in shadowlab's Y-up world.
    #[inline]
    pub fn turn(self, p: Vec3) -> Vec3 {
        match self {
            UpAxis::Y => p,
            UpAxis::Z => vec3(p.x, p.z, -p.y),
            UpAxis::NegZ => vec3(p.x, -p.z, p.y),
            UpAxis::NegY => vec3(p.x, -p.y, -p.z),
            UpAxis::X => vec3(-p.y, p.x, p.z),
            UpAxis::NegX => vec3(p.y, -p.x, p.z),
        }
    }

    fn turn_light(self, l: Light) -> Light {
        match l {
            Light::Directional { to_light } => Light::Directional {
                to_light: self.turn(to_light),
            },
            Light::Spot {
                position,
                target,
                fov_deg,
            } => Light::Spot {
                position: self.turn(position),
                target: self.turn(target),
                fov_deg,
            },
            Light::Point { position } => Light::Point {
                position: self.turn(position),
            },
        }
    }

    fn turn_area_light(self, a: AreaLight) -> AreaLight {
        match a {
            AreaLight::Rect {
                centre,
                edge_u,
                edge_v,
            } => AreaLight::Rect {
                centre: self.turn(centre),
                edge_u: self.turn(edge_u),
                edge_v: self.turn(edge_v),
            },
            AreaLight::Disk {
                centre,
                normal,
                radius,
            } => AreaLight::Disk {
                centre: self.turn(centre),
                normal: self.turn(normal),
                radius,
            },
            AreaLight::Sphere { centre, radius } => AreaLight::Sphere {
                centre: self.turn(centre),
                radius,
            },
            AreaLight::Distant {
                to_light,
                angle_deg,
            } => AreaLight::Distant {
                to_light: self.turn(to_light),
                angle_deg,
            },
        }
    }
}

impl fmt::Display for UpAxis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for UpAxis {
    type Err = String;

    /// Parses `x`, `y`, `z`, `-x`, `-y` or `-z` (also `+x`…, any case); the error is a
    /// phrase naming the value and the choices.
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        Ok(match t.strip_prefix('+').unwrap_or(&t) {
            "x" => UpAxis::X,
            "y" => UpAxis::Y,
            "z" => UpAxis::Z,
            "-x" => UpAxis::NegX,
            "-y" => UpAxis::NegY,
            "-z" => UpAxis::NegZ,
            _ => {
                let shown: String = s.chars().take(24).collect();
                return Err(format!("{shown:?} is not an axis (use {})", UpAxis::NAMES));
            }
        })
    }
}

impl Scene {
    /// Turns everything the scene holds — triangles, its own camera, camera path and
    /// lights — from a file whose up axis is `up` into shadowlab's Y-up world. Nothing
    /// changes for [`UpAxis::Y`].
    pub fn turn_up(&mut self, up: UpAxis) {
        if up == UpAxis::Y {
            return;
        }
        for v in [&mut self.v0, &mut self.v1, &mut self.v2] {
            for p in v.iter_mut() {
                *p = up.turn(*p);
            }
        }
        if let Some(c) = &mut self.camera {
            c.eye = up.turn(c.eye);
            c.target = up.turn(c.target);
            c.up = up.turn(c.up);
        }
        if let Some(path) = &mut self.camera_path {
            for k in &mut path.keys {
                k.eye = up.turn(k.eye);
                k.target = up.turn(k.target);
            }
        }
        self.light = self.light.map(|l| up.turn_light(l));
        self.area_light = self.area_light.map(|a| up.turn_area_light(a));
        self.recompute_bounds();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat3;

    #[test]
    fn every_turn_is_a_proper_rotation_taking_its_axis_up() {
        let axes = [
            (UpAxis::X, Vec3::X),
            (UpAxis::Y, Vec3::Y),
            (UpAxis::Z, Vec3::Z),
            (UpAxis::NegX, -Vec3::X),
            (UpAxis::NegY, -Vec3::Y),
            (UpAxis::NegZ, -Vec3::Z),
        ];
        for (up, axis) in axes {
            assert_eq!(up.turn(axis), Vec3::Y, "{up}");
            let m = Mat3::from_cols(up.turn(Vec3::X), up.turn(Vec3::Y), up.turn(Vec3::Z));
            assert_eq!(m.determinant(), 1.0, "{up} is a rotation, not a mirror");
            assert_eq!(m * m.transpose(), Mat3::IDENTITY, "{up}");
            assert_eq!(up.name().parse::<UpAxis>(), Ok(up));
        }
        assert_eq!(UpAxis::Z.turn(vec3(1.0, 2.0, 3.0)), vec3(1.0, 3.0, -2.0));
        assert_eq!("+Z".parse::<UpAxis>(), Ok(UpAxis::Z));
        assert_eq!(serde_json::to_string(&UpAxis::NegZ).unwrap(), "\"-z\"");
        let bad = "w".parse::<UpAxis>().unwrap_err();
        assert!(bad.contains("\"w\"") && bad.contains("-z"), "{bad}");
    }
}
