//! The scene flags of `render` and `compare` turned into a [`Setup`]: the scene is
//! loaded, the overrides applied, the camera and light resolved and checked.

use super::parse::{parse_kvs, parse_vec3};
use crate::args::SceneArgs;
use crate::failure::{bad_input, InputContext};
use anyhow::{Context, Result};
use shadowlab::area_light::{self, AreaLight};
use shadowlab::auto_light;
use shadowlab::camera::{Camera, Projection};
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::scene::{self, Scene, UpAxis};
use std::collections::BTreeMap;

/// A loaded scene with its resolved camera (first frame), light and path.
pub struct Setup {
    /// The scene.
    pub scene: Scene,
    /// The camera of the first frame (its depth range not yet fitted).
    pub camera: Camera,
    /// The light: the punctual one, or the area light's punctual stand-in that hard
    /// techniques use (its centre).
    pub light: Light,
    /// The area light, when the light has an area.
    pub area: Option<AreaLight>,
    /// Light samples per pixel under an area light (`--light-samples`).
    pub light_samples: u32,
    /// Frames to render.
    pub frames: usize,
    /// Whether the layers behind semi-transparent surfaces are shaded too.
    pub layers: bool,
    /// The `--scene` argument as given.
    pub source: String,
    /// The `--scene-param` values.
    pub params: BTreeMap<String, String>,
    /// The mesh file's up axis (`--up`).
    pub up: UpAxis,
    /// Whether OBJ `map_Kd` alpha cuts materials out (`--obj-kd-alpha`).
    pub obj_kd_alpha: bool,
}

/// The most frames a sequence may have.
pub const MAX_FRAMES: usize = 100_000;

impl Setup {
    /// Refuses an image whose camera pass and `results` kept results (a render keeps one;
    /// compare one per run and the reference's) would need more memory than this process
    /// may use, naming the size and the estimate, before anything is rendered.
    pub fn check_pixel_budget(&self, results: usize) -> Result<()> {
        let (w, h) = (self.camera.width, self.camera.height);
        shadowlab::limits::check_frame(w, h, results, "--width/--height")?;
        Ok(())
    }

    /// The camera of frame `i` (the scene's path when it has one, else the still camera),
    /// with its depth range fitted to the scene.
    pub fn camera_at(&self, i: usize) -> Camera {
        let mut c = match &self.scene.camera_path {
            Some(path) if self.frames > 1 => path.camera_at(&self.camera, i, self.frames),
            _ => self.camera,
        };
        c.fit_depth_range(&self.scene.bounds);
        c
    }
}

/// Parses a `--light` value: a punctual light, or an area light with its punctual
/// stand-in.
pub fn parse_light(s: &str) -> Result<(Light, Option<AreaLight>)> {
    let parts: Vec<&str> = s.split(':').collect();
    let number = |f: &str, what: &str| -> Result<f32> {
        f.trim()
            .parse()
            .input_context(|| format!("--light {what} {f:?} is not a number"))
    };
    let area = match parts.as_slice() {
        ["rect", c, u, v] => Some(AreaLight::Rect {
            centre: parse_vec3(c, "--light centre")?,
            edge_u: parse_vec3(u, "--light edge")?,
            edge_v: parse_vec3(v, "--light edge")?,
        }),
        ["disk", c, n, r] => Some(AreaLight::Disk {
            centre: parse_vec3(c, "--light centre")?,
            normal: parse_vec3(n, "--light normal")?,
            radius: number(r, "radius")?,
        }),
        ["sphere", c, r] => Some(AreaLight::Sphere {
            centre: parse_vec3(c, "--light centre")?,
            radius: number(r, "radius")?,
        }),
        _ => None,
    };
    if let Some(a) = area {
        a.validate().context("--light")?;
        let a = a.normalized();
        return Ok((a.punctual(), Some(a)));
    }
    let light = match parts.as_slice() {
        ["directional", d] => Light::Directional {
            to_light: parse_vec3(d, "--light direction")?,
        },
        ["point", p] => Light::Point {
            position: parse_vec3(p, "--light position")?,
        },
        ["spot", p, t, f] => Light::Spot {
            position: parse_vec3(p, "--light position")?,
            target: parse_vec3(t, "--light target")?,
            fov_deg: f
                .trim()
                .parse()
                .input_context(|| format!("--light cone angle {f:?} is not a number"))?,
        },
        _ => {
            return Err(bad_input(format!(
            "--light {s:?} is not directional:DX,DY,DZ, point:X,Y,Z, spot:X,Y,Z:TX,TY,TZ:FOV_DEG, \
             rect:X,Y,Z:UX,UY,UZ:VX,VY,VZ, disk:X,Y,Z:NX,NY,NZ:R or sphere:X,Y,Z:R"
        )))
        }
    };
    light.validate().context("--light")?;
    Ok((light.normalized(), None))
}

/// The light of a run: `--light` or the scene's, sized by `--light-size` when given.
fn resolve_light(
    args: &SceneArgs,
    scene: &Scene,
    camera: &Camera,
) -> Result<(Light, Option<AreaLight>)> {
    let (light, area) = match &args.light {
        Some(l) => parse_light(l)?,
        None => (scene_light(scene, camera)?, scene.area_light),
    };
    size_light(light, area, args.light_size)
}

/// The light `(light, area)` given the size of `--light-size` when there is one: a
/// punctual light becomes an area light ([`AreaLight::sized`]); an area light is refused.
pub fn size_light(
    light: Light,
    area: Option<AreaLight>,
    size: Option<f32>,
) -> Result<(Light, Option<AreaLight>)> {
    let Some(size) = size else {
        return Ok((light, area));
    };
    if let Some(a) = area {
        return Err(bad_input(format!(
            "--light-size {size} sizes a punctual light, and the light is already a {} area light",
            a.kind()
        )));
    }
    let a = AreaLight::sized(&light.normalized(), size)
        .map_err(|e| bad_input(format!("--light-size {size}: {e}")))?;
    Ok((light, Some(a)))
}

/// Loads the scene of `args` and applies every override: the image size, camera and
/// light flags; the light, unless given, as the scene has it or chosen for the camera.
pub fn resolve(args: &SceneArgs) -> Result<Setup> {
    if args.frames == 0 || args.frames > MAX_FRAMES {
        return Err(bad_input(format!(
            "--frames {} is outside 1..={MAX_FRAMES}",
            args.frames
        )));
    }
    let params = parse_kvs(&args.scene_params, "--scene-param")?;
    let up: UpAxis = args
        .up
        .parse()
        .map_err(|e| bad_input(format!("--up {e}")))?;
    let options = scene::LoadOptions {
        camera_index: args.camera_index,
        allow_outside_scene_dir: args.allow_outside_scene_dir,
        up,
        obj_kd_alpha: args.obj_kd_alpha,
    };
    let scene = auto_light::load_with(&args.scene, &params, &options)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let mut camera = scene.camera.unwrap_or_else(|| {
        let mut s = scene.clone();
        s.place_camera(false);
        s.camera.expect("place_camera sets a camera")
    });
    apply_camera_flags(args, &mut camera)?;
    area_light::check_light_samples(args.light_samples)
        .map_err(|e| bad_input(format!("--light-samples: {e}")))?;
    // The camera first: the automatic light is chosen from its view.
    check_camera(args, &scene, &camera)?;
    let (light, area) = resolve_light(args, &scene, &camera)?;
    light
        .validate()
        .with_context(|| format!("the light of {}", args.scene))?;
    Ok(Setup {
        scene,
        camera,
        light: light.normalized(),
        area,
        light_samples: args.light_samples,
        frames: args.frames,
        layers: args.layers,
        source: args.scene.clone(),
        params,
        up,
        obj_kd_alpha: args.obj_kd_alpha,
    })
}

/// `--width`, `--height`, `--camera`, `--orthographic` and `--camera-distance` applied to
/// the scene's camera.
fn apply_camera_flags(args: &SceneArgs, camera: &mut Camera) -> Result<()> {
    if let Some(w) = args.width {
        camera.width = w;
    }
    if let Some(h) = args.height {
        camera.height = h;
    }
    if let Some(c) = &args.camera {
        let parts: Vec<&str> = c.split(':').collect();
        if parts.len() < 2 || parts.len() > 3 {
            return Err(bad_input(format!(
                "--camera {c:?} is not EX,EY,EZ:TX,TY,TZ[:FOV_DEG]"
            )));
        }
        camera.eye = parse_vec3(parts[0], "--camera eye")?;
        camera.target = parse_vec3(parts[1], "--camera target")?;
        if let Some(f) = parts.get(2) {
            if camera.is_orthographic() {
                return Err(bad_input(format!(
                    "--camera {c:?} gives a field of view, but the camera is orthographic (its extent is --orthographic's)"
                )));
            }
            camera.fov_y_deg = f
                .trim()
                .parse()
                .input_context(|| format!("--camera field of view {f:?} is not a number"))?;
        }
        if (camera.target - camera.eye)
            .normalize_or_zero()
            .cross(camera.up)
            .length_squared()
            < 1e-8
        {
            camera.up = if camera.up == Vec3::Y {
                Vec3::Z
            } else {
                Vec3::Y
            };
        }
    }
    if let Some(o) = &args.orthographic {
        let ymag = if o.trim() == "auto" {
            camera.orthographic_extent_at_target().1
        } else {
            let v: f32 = o
                .trim()
                .parse()
                .input_context(|| format!("--orthographic {o:?} is neither auto nor a number"))?;
            if !(v.is_finite() && v > 0.0) {
                return Err(bad_input(format!(
                    "--orthographic {o} must be a positive half height"
                )));
            }
            v
        };
        camera.projection = Projection::Orthographic { xmag: ymag, ymag };
    }
    // An orthographic camera keeps its height and its pixels square.
    if let Projection::Orthographic { ymag, .. } = camera.projection {
        let xmag = ymag * camera.aspect();
        if args.width.is_some() || args.height.is_some() || args.orthographic.is_some() {
            camera.projection = Projection::Orthographic { xmag, ymag };
        }
    }
    if let Some(f) = args.camera_distance {
        if !(f.is_finite() && f > 0.0) {
            return Err(bad_input(format!(
                "--camera-distance {f} must be a positive number"
            )));
        }
        camera.scale_distance(f);
    }
    Ok(())
}

/// The light when `--light` is not given: the scene's own, or an automatic one chosen for
/// the camera the shadows are seen from (and printed).
fn scene_light(scene: &Scene, camera: &Camera) -> Result<Light> {
    match scene.light {
        Some(l) if !scene.auto_light => Ok(l),
        auto => {
            let mut seen = *camera;
            seen.fit_depth_range(&scene.bounds);
            seen.validate()?;
            let l = match (auto, scene.camera) {
                (Some(l), Some(c)) if same_view(&c, camera) => l,
                _ => auto_light::choose(scene, &seen),
            };
            if !crate::progress::quiet() {
                if let Light::Directional { to_light: d } = l {
                    println!(
                        "automatic light: directional:{:.4},{:.4},{:.4} (chosen so that its shadows fall where the camera sees them; --light overrides it)",
                        d.x, d.y, d.z
                    );
                }
            }
            Ok(l)
        }
    }
}

/// Checks the camera with its depth range fitted, naming the flags that shaped it.
fn check_camera(args: &SceneArgs, scene: &Scene, camera: &Camera) -> Result<()> {
    let mut check = *camera;
    check.fit_depth_range(&scene.bounds);
    check.validate().with_context(|| {
        let mut from = Vec::new();
        if let Some(c) = &args.camera {
            from.push(format!("--camera {c}"));
        }
        if let Some(f) = args.camera_distance {
            from.push(format!("--camera-distance {f}"));
        }
        if args.width.is_some() || args.height.is_some() {
            from.push("--width/--height".to_string());
        }
        if from.is_empty() {
            format!("the camera of {}", args.scene)
        } else {
            format!("the camera of {} with {}", args.scene, from.join(" and "))
        }
    })?;
    Ok(())
}

/// True when two cameras see the same view (the image size aside).
fn same_view(a: &Camera, b: &Camera) -> bool {
    a.eye == b.eye
        && a.target == b.target
        && a.up == b.up
        && a.fov_y_deg == b.fov_y_deg
        && a.projection == b.projection
}
