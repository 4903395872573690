//! The panel's area lights: a disk, a square or a sphere about a point, or a sun of some
//! angular size, each of one size. The light is the pair `render` reads from `--light`
//! (and `--light-size`): the area light and its punctual stand-in, the light that hard
//! techniques and the shading see.

use super::ui::AreaShape;
use shadowlab::area_light::AreaLight;
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::scene::Scene;

/// The size of a new area light: this share of the scene's diagonal (a radius or half a
/// side), or for a sun its angular diameter in degrees.
const SIZE_SHARE: f32 = 0.05;
const SUN_DEG: f32 = 2.0;

/// The shape and size of an area light: the radius of a disk or sphere, half the longer
/// side of a rectangle, a sun's angular diameter.
pub fn shape_of(a: &AreaLight) -> (AreaShape, f32) {
    match *a {
        AreaLight::Disk { radius, .. } => (AreaShape::Disk, radius),
        AreaLight::Sphere { radius, .. } => (AreaShape::Sphere, radius),
        AreaLight::Rect { edge_u, edge_v, .. } => {
            (AreaShape::Rect, edge_u.length().max(edge_v.length()) / 2.0)
        }
        AreaLight::Distant { angle_deg, .. } => (AreaShape::Sun, angle_deg),
    }
}

/// The size a new area light of `shape` starts with in `scene`.
pub fn default_size(shape: AreaShape, scene: &Scene) -> f32 {
    match shape {
        AreaShape::Sun => SUN_DEG,
        _ => scene.bounds.diagonal() * SIZE_SHARE,
    }
}

/// The area light of `shape` and `size` where `light` is, with its punctual stand-in: a
/// disk or square about the light's position (a directional light's: the scene's centre
/// plus its diagonal along the direction) facing the scene's centre, a sphere about it,
/// or a sun in the light's direction. A disk at a spot light is the spot given a size
/// (as `--light-size` makes it: facing its target, keeping its cone).
pub fn make(shape: AreaShape, size: f32, light: &Light, scene: &Scene) -> (Light, AreaLight) {
    let (centre, diagonal) = (scene.bounds.center(), scene.bounds.diagonal());
    let position = match *light {
        Light::Directional { to_light } => centre + to_light.normalize() * diagonal,
        Light::Point { position } | Light::Spot { position, .. } => position,
    };
    let facing = (centre - position).try_normalize().unwrap_or(-Vec3::Y);
    let at = Light::Point { position };
    match shape {
        AreaShape::Sun => {
            let to_light = match *light {
                Light::Directional { to_light } => to_light.normalize(),
                _ => (-facing).normalize(),
            };
            let sun = AreaLight::Distant {
                to_light,
                angle_deg: size,
            };
            (Light::Directional { to_light }, sun)
        }
        AreaShape::Disk => match *light {
            Light::Spot { .. } => match AreaLight::sized(light, size) {
                Ok(a) => (*light, a),
                Err(_) => (at, disk(position, facing, size)),
            },
            _ => (at, disk(position, facing, size)),
        },
        AreaShape::Rect => {
            let side = facing.cross(Vec3::Y);
            let u = if side.length() > 1e-3 {
                side.normalize()
            } else {
                facing.cross(Vec3::X).normalize()
            };
            let v = facing.cross(u).normalize();
            let rect = AreaLight::Rect {
                centre: position,
                edge_u: u * (2.0 * size),
                edge_v: v * (2.0 * size),
            };
            (at, rect)
        }
        AreaShape::Sphere => (
            at,
            AreaLight::Sphere {
                centre: position,
                radius: size,
            },
        ),
    }
}

fn disk(centre: Vec3, normal: Vec3, radius: f32) -> AreaLight {
    AreaLight::Disk {
        centre,
        normal,
        radius,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab::math::vec3;

    #[test]
    fn each_shape_keeps_its_size_and_place() {
        let scene = shadowlab::scene::load("chessboard", &Default::default()).unwrap();
        let point = Light::Point {
            position: vec3(1.0, 5.0, 2.0),
        };
        for (shape, _) in AreaShape::ALL {
            let size = default_size(shape, &scene);
            let (stand_in, a) = make(shape, size, &point, &scene);
            a.validate().unwrap();
            let (read, read_size) = shape_of(&a);
            assert_eq!(read, shape);
            // A square's half side comes back from its edge vectors' length.
            assert!(
                (read_size - size).abs() <= size * 1e-6,
                "{shape:?}: {read_size}"
            );
            match shape {
                AreaShape::Sun => assert!(matches!(stand_in, Light::Directional { .. })),
                _ => assert_eq!(stand_in, point, "{shape:?}"),
            }
        }
    }
}
