//! The `render` command line that reproduces what the viewer shows: the scene flags as
//! given, the window's size, the camera and light as they are now, the technique and its
//! parameters. Numbers are written in the shortest form that reads back to the same
//! `f32`, and the viewer keeps its light as that text reads back, so the command renders
//! the very same pixels.

use crate::args::SceneArgs;
use crate::config::scene::parse_light;
use anyhow::Result;
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

/// What a view is made of, for its command line.
pub struct ViewState<'a> {
    /// The scene flags as given (the window's size filled in).
    pub scene: &'a SceneArgs,
    /// The camera.
    pub camera: &'a Camera,
    /// The light.
    pub light: &'a Light,
    /// The technique, as the command line spells it.
    pub technique: &'a str,
    /// Its parameters set by the user.
    pub params: &'a [(String, String)],
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
        "--light".into(),
        light_arg(v.light),
        "--technique".into(),
        v.technique.to_string(),
    ]);
    if let Projection::Orthographic { ymag, .. } = v.camera.projection {
        a.extend(["--orthographic".into(), ymag.to_string()]);
    }
    for (k, val) in v.params {
        a.extend(["--param".into(), format!("{k}={val}")]);
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
    fn odd_arguments_are_quoted() {
        let line = command_line(&["--scene".into(), "my mesh's.obj".into(), "a,b:c".into()]);
        assert_eq!(line, "shadowlab --scene 'my mesh'\\''s.obj' a,b:c");
    }
}
