//! The fly camera and the dragged light: mouse look turns the view direction about the
//! camera's up (yaw) and its right (pitch, kept short of straight up or down); the flight
//! keys move eye and target together by a step proportional to the scene's size; a
//! right-button drag turns a directional light's direction, or a point or spot light's
//! position about what it circles, by azimuth and elevation about the camera's up.

use super::input::Move;
use glam::Quat;
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::scene::Scene;
use std::collections::BTreeSet;

/// Degrees the view turns per pixel of a drag.
pub const LOOK_DEG_PER_PIXEL: f32 = 0.2;

/// Degrees the light turns per pixel of a drag.
pub const LIGHT_DEG_PER_PIXEL: f32 = 0.5;

/// One flight step as a share of the scene's bounding-box diagonal.
pub const STEP_OF_DIAGONAL: f32 = 0.01;

/// The closest the view direction or the light comes to the up axis, in degrees.
const MAX_ELEVATION_DEG: f32 = 89.0;

/// Turns `v` by `yaw_deg` about `up` and raises it by `pitch_deg` towards `up`, its
/// elevation kept within ±[`MAX_ELEVATION_DEG`].
fn turn(v: Vec3, up: Vec3, yaw_deg: f32, pitch_deg: f32) -> Vec3 {
    let up = up.normalize();
    let len = v.length();
    let d = Quat::from_axis_angle(up, yaw_deg.to_radians()) * (v / len);
    let elevation = d.dot(up).clamp(-1.0, 1.0).asin().to_degrees();
    let wanted = (elevation + pitch_deg).clamp(-MAX_ELEVATION_DEG, MAX_ELEVATION_DEG);
    let flat = (d - up * d.dot(up)).normalize_or_zero();
    if flat == Vec3::ZERO {
        return v;
    }
    let e = wanted.to_radians();
    (flat * e.cos() + up * e.sin()) * len
}

/// Turns the camera's view by a drag of (dx, dy) pixels: right turns right, down looks
/// down.
pub fn look(camera: &mut Camera, dx: f32, dy: f32) {
    let v = camera.target - camera.eye;
    let turned = turn(
        v,
        camera.up,
        -dx * LOOK_DEG_PER_PIXEL,
        -dy * LOOK_DEG_PER_PIXEL,
    );
    camera.target = camera.eye + turned;
}

/// Moves eye and target one step for each held flight key.
pub fn fly(camera: &mut Camera, held: &BTreeSet<Move>, scene: &Scene) {
    let step = scene.bounds.diagonal() * STEP_OF_DIAGONAL;
    let (right, up, forward) = axes(camera);
    let mut d = Vec3::ZERO;
    for m in held {
        d += match m {
            Move::Forward => forward,
            Move::Back => -forward,
            Move::Right => right,
            Move::Left => -right,
            Move::Up => up,
            Move::Down => -up,
        };
    }
    camera.eye += d * step;
    camera.target += d * step;
}

/// The camera's right, up and forward unit vectors.
fn axes(camera: &Camera) -> (Vec3, Vec3, Vec3) {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    (right, right.cross(forward), forward)
}

/// The light turned by a drag of (dx, dy) pixels about the camera's up: a direction
/// turns, a point light circles the scene's centre, a spot light circles its target.
pub fn drag_light(light: &Light, camera: &Camera, scene: &Scene, dx: f32, dy: f32) -> Light {
    let (yaw, pitch) = (dx * LIGHT_DEG_PER_PIXEL, -dy * LIGHT_DEG_PER_PIXEL);
    match *light {
        Light::Directional { to_light } => Light::Directional {
            to_light: turn(to_light, camera.up, yaw, pitch),
        },
        Light::Point { position } => {
            let c = scene.bounds.center();
            Light::Point {
                position: c + turn(position - c, camera.up, yaw, pitch),
            }
        }
        Light::Spot {
            position,
            target,
            fov_deg,
        } => Light::Spot {
            position: target + turn(position - target, camera.up, yaw, pitch),
            target,
            fov_deg,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab::math::vec3;

    #[test]
    fn turning_keeps_length_and_stops_short_of_the_pole() {
        let v = vec3(3.0, 0.0, 4.0);
        let t = turn(v, Vec3::Y, 90.0, 0.0);
        assert!((t.length() - 5.0).abs() < 1e-5);
        assert!(t.y.abs() < 1e-5 && (t.dot(v)).abs() < 1e-4);
        let up = turn(v, Vec3::Y, 0.0, 500.0);
        let elev = (up.y / up.length()).asin().to_degrees();
        assert!((elev - MAX_ELEVATION_DEG).abs() < 1e-3, "{elev}");
    }

    #[test]
    fn looking_right_turns_the_view_right() {
        let mut c = Camera::look_at(Vec3::ZERO, vec3(0.0, 0.0, -1.0), 45.0, 64, 48);
        let (right, _, _) = axes(&c);
        look(&mut c, 10.0, 0.0);
        assert!((c.target - c.eye).dot(right) > 0.0);
    }
}
