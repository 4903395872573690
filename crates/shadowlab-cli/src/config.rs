//! Raw command-line arguments turned into a validated configuration before any work
//! starts: the scene is loaded, overrides applied, the camera and light resolved.

use anyhow::{bail, Context, Result};
use shadowlab::auto_light;
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec3};
use shadowlab::scene::{self, Scene};
use std::collections::BTreeMap;

/// The scene-related flags every command shares.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// A built-in scene name (see `shadowlab scenes`), a `.toml` scene file, or a mesh
    /// (`.obj`, `.ply`, `.gltf`, `.glb`).
    #[arg(long, default_value = "bunny")]
    pub scene: String,
    /// A built-in scene's parameter, e.g. `count=1000000` for random-triangles.
    #[arg(long = "scene-param", value_name = "K=V")]
    pub scene_params: Vec<String>,
    /// Image width in pixels.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera override: `EX,EY,EZ:TX,TY,TZ[:FOV_DEG]`.
    #[arg(long, value_name = "EYE:TARGET[:FOV]")]
    pub camera: Option<String>,
    /// Move the camera along its view ray to F times its distance from its target.
    #[arg(
        long = "camera-distance",
        value_name = "F",
        allow_negative_numbers = true
    )]
    pub camera_distance: Option<f32>,
    /// Which of the scene's cameras to use: a glTF file's camera nodes in the order its
    /// node hierarchy is walked (0 = the first).
    #[arg(long = "camera-index", value_name = "N", default_value_t = 0)]
    pub camera_index: usize,
    /// Light override: `directional:DX,DY,DZ`, `point:X,Y,Z` or `spot:X,Y,Z:TX,TY,TZ:FOV_DEG`.
    #[arg(long)]
    pub light: Option<String>,
    /// Render the camera path (or a still camera) this many times; reports describe the last.
    #[arg(long, default_value_t = 1)]
    pub frames: usize,
    /// Shade the surfaces behind semi-transparent ones too, each with its own shadow term,
    /// and composite them (techniques afsm and raytrace; the others shade the nearest
    /// surface only).
    #[arg(long)]
    pub layers: bool,
    /// Let a scene file's references (glTF buffer URIs, OBJ `mtllib`, TOML mesh `file`)
    /// name files outside its folder; by default they are refused.
    #[arg(long = "allow-outside-scene-dir")]
    pub allow_outside_scene_dir: bool,
}

/// A loaded scene with its resolved camera (first frame), light and path.
pub struct Setup {
    pub scene: Scene,
    pub camera: Camera,
    pub light: Light,
    pub frames: usize,
}

/// The most frames a sequence may have.
pub const MAX_FRAMES: usize = 100_000;

/// Bytes a frame holds per pixel whatever the techniques: the camera pass's samples (68),
/// the rasterizer's depth and id tiles while they are assembled (16), the shaded images
/// and the animation frame (about 12), and the technique's per-pixel working set (afsm's
/// samples and lists, the largest, about 32).
pub const BYTES_PER_PIXEL: u64 = 128;

/// Bytes each result kept until the end of a run holds per pixel: its visibility (16),
/// with the error image and the comparison's working set in `compare` (16).
pub const RESULT_BYTES_PER_PIXEL: u64 = 32;

impl Setup {
    /// Refuses an image whose camera pass and `results` kept results (a render keeps one;
    /// compare one per run and the reference's) would need more memory than this process
    /// may use, naming the size and the estimate, before anything is rendered.
    pub fn check_pixel_budget(&self, results: usize) -> Result<()> {
        let (w, h) = (self.camera.width, self.camera.height);
        let pixels = w as u64 * h as u64;
        let per = BYTES_PER_PIXEL + RESULT_BYTES_PER_PIXEL * results as u64;
        shadowlab::limits::check_bytes(
            || {
                format!(
                    "a {w}x{h} image (--width/--height) with {results} result(s) kept: {pixels} pixels"
                )
            },
            pixels.saturating_mul(per),
        )?;
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

fn parse_kv(s: &str, flag: &str) -> Result<(String, String)> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => bail!("{flag} {s:?} is not of the form KEY=VALUE"),
    }
}

/// Parses repeated `K=V` flags.
pub fn parse_kvs(items: &[String], flag: &str) -> Result<BTreeMap<String, String>> {
    items.iter().map(|s| parse_kv(s, flag)).collect()
}

/// Parses `X,Y,Z`.
pub fn parse_vec3(s: &str, what: &str) -> Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{what} {s:?} is not three comma-separated numbers"))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        bail!("{what} {s:?} is not three finite comma-separated numbers");
    }
    Ok(vec3(v[0], v[1], v[2]))
}

/// Parses a `--light` value.
pub fn parse_light(s: &str) -> Result<Light> {
    let parts: Vec<&str> = s.split(':').collect();
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
                .with_context(|| format!("--light cone angle {f:?} is not a number"))?,
        },
        _ => bail!(
            "--light {s:?} is not directional:DX,DY,DZ, point:X,Y,Z or spot:X,Y,Z:TX,TY,TZ:FOV_DEG"
        ),
    };
    light.validate().context("--light")?;
    Ok(light.normalized())
}

impl SceneArgs {
    /// Loads the scene and applies every override.
    pub fn resolve(&self) -> Result<Setup> {
        if self.frames == 0 || self.frames > MAX_FRAMES {
            bail!("--frames {} is outside 1..={MAX_FRAMES}", self.frames);
        }
        let params = parse_kvs(&self.scene_params, "--scene-param")?;
        let options = scene::LoadOptions {
            camera_index: self.camera_index,
            allow_outside_scene_dir: self.allow_outside_scene_dir,
        };
        let scene = auto_light::load_with(&self.scene, &params, &options)?;
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
        let mut camera = scene.camera.unwrap_or_else(|| {
            let mut s = scene.clone();
            s.place_camera(false);
            s.camera.expect("place_camera sets a camera")
        });
        if let Some(w) = self.width {
            camera.width = w;
        }
        if let Some(h) = self.height {
            camera.height = h;
        }
        if let Some(c) = &self.camera {
            let parts: Vec<&str> = c.split(':').collect();
            if parts.len() < 2 || parts.len() > 3 {
                bail!("--camera {c:?} is not EX,EY,EZ:TX,TY,TZ[:FOV_DEG]");
            }
            camera.eye = parse_vec3(parts[0], "--camera eye")?;
            camera.target = parse_vec3(parts[1], "--camera target")?;
            if let Some(f) = parts.get(2) {
                camera.fov_y_deg = f
                    .trim()
                    .parse()
                    .with_context(|| format!("--camera field of view {f:?} is not a number"))?;
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
        if let Some(f) = self.camera_distance {
            if !(f.is_finite() && f > 0.0) {
                bail!("--camera-distance {f} must be a positive number");
            }
            camera.scale_distance(f);
        }
        let framed = scene.camera;
        let light = match &self.light {
            Some(l) => parse_light(l)?,
            None => match scene.light {
                Some(l) if !scene.auto_light => l,
                auto => {
                    // Chosen for the camera the shadows are seen from.
                    let mut seen = camera;
                    seen.fit_depth_range(&scene.bounds);
                    seen.validate()?;
                    let l = match (auto, framed) {
                        (Some(l), Some(c)) if same_view(&c, &camera) => l,
                        _ => auto_light::choose(&scene, &seen),
                    };
                    if !crate::progress::quiet() {
                        if let Light::Directional { to_light: d } = l {
                            println!(
                                "automatic light: directional:{:.4},{:.4},{:.4} (chosen so that its shadows fall where the camera sees them; --light overrides it)",
                                d.x, d.y, d.z
                            );
                        }
                    }
                    l
                }
            },
        };
        light
            .validate()
            .with_context(|| format!("the light of {}", self.scene))?;
        let mut check = camera;
        check.fit_depth_range(&scene.bounds);
        check.validate().with_context(|| {
            let mut from = Vec::new();
            if let Some(c) = &self.camera {
                from.push(format!("--camera {c}"));
            }
            if let Some(f) = self.camera_distance {
                from.push(format!("--camera-distance {f}"));
            }
            if self.width.is_some() || self.height.is_some() {
                from.push("--width/--height".to_string());
            }
            if from.is_empty() {
                format!("the camera of {}", self.scene)
            } else {
                format!("the camera of {} with {}", self.scene, from.join(" and "))
            }
        })?;
        Ok(Setup {
            scene,
            camera,
            light: light.normalized(),
            frames: self.frames,
        })
    }
}

/// True when two cameras see the same view (the image size aside).
fn same_view(a: &Camera, b: &Camera) -> bool {
    a.eye == b.eye && a.target == b.target && a.up == b.up && a.fov_y_deg == b.fov_y_deg
}

/// `T.K=V` technique parameters of `compare`, grouped by technique.
pub fn parse_prefixed_params(items: &[String]) -> Result<BTreeMap<String, Vec<(String, String)>>> {
    let mut out: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for s in items {
        let (k, v) = parse_kv(s, "--param")?;
        let Some((t, key)) = k.split_once('.') else {
            bail!("--param {s:?} in compare must name its technique: TECHNIQUE.KEY=VALUE, e.g. sm.resolution=4096");
        };
        out.entry(t.to_string())
            .or_default()
            .push((key.to_string(), v));
    }
    Ok(out)
}
