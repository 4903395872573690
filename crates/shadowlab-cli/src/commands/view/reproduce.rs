//! The `render` command line that reproduces what the viewer shows: the scene flags as
//! given, the window's size, the camera and light as they are now, the technique and its
//! parameters. Numbers are written in the shortest form that reads back to the same
//! `f32`, and the viewer keeps its light as that text reads back, so the command renders
//! the very same pixels.

use crate::args::SceneArgs;
use crate::config::scene::{parse_light, size_light};
use anyhow::Result;
use shadowlab::area_light::{AreaLight, DEFAULT_LIGHT_SAMPLES};
use shadowlab::camera::{Camera, Projection};
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use std::path::Path;

/// `X,Y,Z`, each number read back exactly.
fn vec3_arg(v: Vec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

/// The `--camera` value of a camera (an orthographic one's extent goes to
/// `--orthographic`).
pub fn camera_arg(c: &Camera) -> String {
    match c.projection {
        Projection::Perspective => {
            format!("{}:{}:{}", vec3_arg(c.eye), vec3_arg(c.target), c.fov_y_deg)
        }
        Projection::Orthographic { .. } => format!("{}:{}", vec3_arg(c.eye), vec3_arg(c.target)),
    }
}

/// The `--light` value of a light.
pub fn light_arg(l: &Light) -> String {
    match *l {
        Light::Directional { to_light } => format!("directional:{}", vec3_arg(to_light)),
        Light::Point { position } => format!("point:{}", vec3_arg(position)),
        Light::Spot {
            position,
            target,
            fov_deg,
        } => format!("spot:{}:{}:{fov_deg}", vec3_arg(position), vec3_arg(target)),
    }
}

/// The light as `render --light` reads its text: what the viewer shows.
pub fn as_rendered(l: &Light) -> Result<Light> {
    Ok(parse_light(&light_arg(l))?.0.normalized())
}

/// The `--light` value of an area light that `--light` can name (not a sun).
fn area_arg(a: &AreaLight) -> Option<String> {
    Some(match *a {
        AreaLight::Rect {
            centre,
            edge_u,
            edge_v,
        } => format!(
            "rect:{}:{}:{}",
            vec3_arg(centre),
            vec3_arg(edge_u),
            vec3_arg(edge_v)
        ),
        AreaLight::Disk {
            centre,
            normal,
            radius,
        } => format!("disk:{}:{}:{radius}", vec3_arg(centre), vec3_arg(normal)),
        AreaLight::Sphere { centre, radius } => format!("sphere:{}:{radius}", vec3_arg(centre)),
        AreaLight::Distant { .. } => return None,
    })
}

/// The `--light` value and the `--light-size` of a light `l` with its area light: an area
/// light named by `--light` (its stand-in then its centre), a sun as a directional light
/// given a size, a spot light given a size as that.
pub fn light_args(l: &Light, area: Option<&AreaLight>) -> (String, Option<f32>) {
    let Some(a) = area else {
        return (light_arg(l), None);
    };
    match (*a, area_arg(a)) {
        (
            AreaLight::Distant {
                to_light,
                angle_deg,
            },
            _,
        ) => (light_arg(&Light::Directional { to_light }), Some(angle_deg)),
        (_, Some(text)) if a.punctual() == *l => (text, None),
        (AreaLight::Disk { radius, .. }, _) if AreaLight::sized(l, radius).ok() == Some(*a) => {
            (light_arg(l), Some(radius))
        }
        (_, text) => (text.unwrap_or_else(|| light_arg(l)), None),
    }
}

/// The light and area light as `render --light` (and `--light-size`) read their text:
/// what the viewer shows.
pub fn as_rendered_area(l: &Light, area: Option<&AreaLight>) -> Result<(Light, Option<AreaLight>)> {
    let (text, size) = light_args(l, area);
    let (light, area) = parse_light(&text)?;
    let (light, area) = size_light(light.normalized(), area, size)?;
    Ok((light.normalized(), area))
}

/// What a view is made of, for its command line.
pub struct ViewState<'a> {
    /// The scene flags as given (the window's size filled in).
    pub scene: &'a SceneArgs,
    /// The camera.
    pub camera: &'a Camera,
    /// The light (an area light's stand-in).
    pub light: &'a Light,
    /// The area light, when the light has an area.
    pub area: Option<&'a AreaLight>,
    /// Light samples per pixel under an area light.
    pub light_samples: u32,
    /// The technique, as the command line spells it.
    pub technique: &'a str,
    /// Its parameters set by the user.
    pub params: &'a [(String, String)],
    /// True when the view's camera pass is the GPU's own (`--camera-pass gpu`).
    pub gpu_camera_pass: bool,
}

/// The arguments of `shadowlab render` (without the program's name) that reproduce the
/// view, writing `output`.
pub fn render_args(v: &ViewState, output: &Path) -> Vec<String> {
    let s = v.scene;
    let mut a: Vec<String> = vec!["render".into(), "--scene".into(), s.scene.clone()];
    for p in &s.scene_params {
        a.extend(["--scene-param".into(), p.clone()]);
    }
    if s.camera_index != 0 {
        a.extend(["--camera-index".into(), s.camera_index.to_string()]);
    }
    if s.allow_outside_scene_dir {
        a.push("--allow-outside-scene-dir".into());
    }
    if s.up.trim() != "y" {
        a.push(format!("--up={}", s.up.trim()));
    }
    if !s.obj_kd_alpha {
        a.extend(["--obj-kd-alpha".into(), "false".into()]);
    }
    if s.layers {
        a.push("--layers".into());
    }
    a.extend([
        "--width".into(),
        v.camera.width.to_string(),
        "--height".into(),
        v.camera.height.to_string(),
        "--camera".into(),
        camera_arg(v.camera),
    ]);
    let (light, size) = light_args(v.light, v.area);
    a.extend(["--light".into(), light]);
    if let Some(size) = size {
        a.extend(["--light-size".into(), size.to_string()]);
    }
    if v.area.is_some() && v.light_samples != DEFAULT_LIGHT_SAMPLES {
        a.extend(["--light-samples".into(), v.light_samples.to_string()]);
    }
    a.extend(["--technique".into(), v.technique.to_string()]);
    if let Projection::Orthographic { ymag, .. } = v.camera.projection {
        a.extend(["--orthographic".into(), ymag.to_string()]);
    }
    for (k, val) in v.params {
        a.extend(["--param".into(), format!("{k}={val}")]);
    }
    if v.gpu_camera_pass {
        a.extend(["--camera-pass".into(), "gpu".into()]);
    }
    a.extend(["--output".into(), output.display().to_string()]);
    a
}

/// The command line to paste into a shell: `shadowlab` and the arguments, quoted where
/// a shell would read them otherwise.
pub fn command_line(args: &[String]) -> String {
    let mut out = String::from("shadowlab");
    for a in args {
        out.push(' ');
        let plain = !a.is_empty()
            && a.chars()
                .all(|c| c.is_ascii_alphanumeric() || "_./,:=+-@%".contains(c));
        if plain {
            out.push_str(a);
        } else {
            out.push('\'');
            out.push_str(&a.replace('\'', "'\\''"));
            out.push('\'');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab::math::vec3;

    #[test]
    fn lights_read_back_as_they_are_written() {
        for l in [
            Light::Directional {
                to_light: vec3(0.1, 0.7, -0.3).normalize(),
            },
            Light::Point {
                position: vec3(1.0 / 3.0, 12.5, -7.125),
            },
            Light::Spot {
                position: vec3(2.0, 9.0, 1.0 / 7.0),
                target: vec3(0.0, 0.5, 0.0),
                fov_deg: 37.3,
            },
        ] {
            let once = as_rendered(&l).unwrap();
            assert_eq!(as_rendered(&once).unwrap(), once);
            assert_eq!(light_arg(&once), light_arg(&as_rendered(&once).unwrap()));
        }
    }

    #[test]
    fn area_lights_read_back_as_they_are_written() {
        let point = Light::Point {
            position: vec3(1.0 / 3.0, 12.5, -7.125),
        };
        let spot = Light::Spot {
            position: vec3(2.0, 9.0, 1.0 / 7.0),
            target: vec3(0.0, 0.5, 0.0),
            fov_deg: 37.3,
        };
        let sun = Light::Directional {
            to_light: vec3(0.1, 0.7, -0.3).normalize(),
        };
        let disk = AreaLight::Disk {
            centre: vec3(1.0 / 3.0, 12.5, -7.125),
            normal: vec3(0.2, -1.0, 0.1).normalize(),
            radius: 0.37,
        };
        let rect = AreaLight::Rect {
            centre: vec3(1.0 / 3.0, 12.5, -7.125),
            edge_u: vec3(0.7, 0.0, 0.1),
            edge_v: vec3(0.0, 0.0, 1.0 / 3.0),
        };
        for (l, a, flag) in [
            (disk.punctual(), disk, "disk:"),
            (rect.punctual(), rect, "rect:"),
            (point, AreaLight::sized(&point, 0.25).unwrap(), "sphere:"),
            (spot, AreaLight::sized(&spot, 0.5).unwrap(), "spot:"),
            (sun, AreaLight::sized(&sun, 1.5).unwrap(), "directional:"),
        ] {
            let (l1, a1) = as_rendered_area(&l, Some(&a)).unwrap();
            let a1 = a1.expect("an area light reads back as one");
            assert_eq!(as_rendered_area(&l1, Some(&a1)).unwrap(), (l1, Some(a1)));
            assert!(light_args(&l1, Some(&a1)).0.starts_with(flag), "{a1:?}");
            assert_eq!(a1.kind(), a.kind());
        }
    }

    #[test]
    fn odd_arguments_are_quoted() {
        let line = command_line(&["--scene".into(), "my mesh's.obj".into(), "a,b:c".into()]);
        assert_eq!(line, "shadowlab --scene 'my mesh'\\''s.obj' a,b:c");
    }
}
