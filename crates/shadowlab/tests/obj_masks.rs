//! OBJ alpha cut-outs and up axes, on `masked/cards.obj` (written with its twins by
//! `scripts/make-obj-cards-fixture.py`): a card cut out by a grey `map_d`, a tilted card
//! cut out by its `map_Kd` alpha with repeating texture coordinates. Its shadows equal the
//! reference in the exact techniques, and the reference equals that of the same cards
//! as glTF `MASK` materials (`cards.gltf`); the same file written Z-up (`cards-zup.obj`)
//! and loaded with up axis Z is the Y-up file, to the bit.

mod support;

use shadowlab::auto_light;
use shadowlab::camera::Camera;
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::scene::{LoadOptions, Scene, UpAxis};
use shadowlab::techniques::{self, Frame, Visibility};
use shadowlab::view::ViewSamples;
use support::{assert_same_visibility, data};

/// Texels a side of leaf.png and leaf-mask.png.
const SIDE: usize = 64;

fn load(name: &str, options: &LoadOptions) -> Scene {
    let path = data(name);
    auto_light::load_with(path.to_str().unwrap(), &Default::default(), options)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The scene's automatic camera at 320x240.
fn camera(s: &Scene) -> Camera {
    let mut c = s.camera.expect("a framed mesh has a camera");
    (c.width, c.height) = (320, 240);
    c.fit_depth_range(&s.bounds);
    c
}

/// The reference and the `techniques` of scene `s` seen by its own camera and light.
fn render(s: &Scene, techniques: &[&str]) -> (Visibility, Vec<Visibility>) {
    let camera = camera(s);
    let view = ViewSamples::render(s, &camera);
    let light = s.light.expect("an automatic light");
    let frame = Frame::new(s, &camera, &light, &view);
    let reference = Reference::build(s).visibility(&frame, &[vec2(0.5, 0.5)]);
    let runs = techniques
        .iter()
        .map(|&t| {
            techniques::create(t)
                .unwrap()
                .render(&frame)
                .unwrap_or_else(|e| panic!("{t}: {e}"))
                .visibility
        })
        .collect();
    (reference, runs)
}

fn material<'a>(s: &'a Scene, name: &str) -> &'a shadowlab::scene::Material {
    s.materials
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("material {name}"))
}

/// make-leaf-fixture.py's leaf, restated: 1 inside, 0 outside, at a texel centre.
fn leaf_alpha(u: f32, v: f32) -> u8 {
    if !(0.05 < u && u < 0.95) {
        return 0;
    }
    let half = 0.38 * (std::f32::consts::PI * (u - 0.05) / 0.9).sin();
    u8::from((v - 0.5).abs() < half)
}

#[test]
fn map_d_grey_and_map_kd_alpha_make_masks_and_the_flag_turns_kd_off() {
    let s = load("masked/cards.obj", &LoadOptions::default());
    let d = material(&s, "leaf_d")
        .alpha_mask
        .as_ref()
        .expect("map_d mask");
    let kd = material(&s, "leaf_kd")
        .alpha_mask
        .as_ref()
        .expect("map_Kd mask");
    assert!(material(&s, "floor").alpha_mask.is_none());
    for m in [d, kd] {
        assert_eq!((m.cutoff, m.factor), (0.5, 1.0));
        assert_eq!(
            (m.texture.width, m.texture.height),
            (SIDE as u32, SIDE as u32)
        );
    }
    // The grey map_d and leaf.png's alpha are the same leaf.
    for j in 0..SIDE {
        for i in 0..SIDE {
            let want = 255 * leaf_alpha((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
            assert_eq!(
                d.texture.alpha[j * SIDE + i],
                want,
                "map_d texel ({i}, {j})"
            );
            assert_eq!(
                kd.texture.alpha[j * SIDE + i],
                want,
                "map_Kd texel ({i}, {j})"
            );
        }
    }
    let said: Vec<&String> = s.warnings.iter().filter(|w| w.contains("map_Kd")).collect();
    assert_eq!(said.len(), 1, "{:?}", s.warnings);
    assert!(said[0].contains("\"leaf_kd\"") && !said[0].contains("leaf_d\""));
    assert_eq!(s.uv.len(), s.len());

    let off = LoadOptions {
        obj_kd_alpha: false,
        ..Default::default()
    };
    let s = load("masked/cards.obj", &off);
    assert!(material(&s, "leaf_d").alpha_mask.is_some());
    assert!(material(&s, "leaf_kd").alpha_mask.is_none());
    assert!(
        !s.warnings.iter().any(|w| w.contains("map_Kd")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn cut_out_shadows_equal_the_reference_and_the_gltf_mask_twin() {
    let obj = load("masked/cards.obj", &LoadOptions::default());
    let gltf = load("masked/cards.gltf", &LoadOptions::default());
    assert_eq!(obj.v0, gltf.v0);
    assert_eq!(
        obj.uv, gltf.uv,
        "v turned to count from the top row, as glTF's"
    );
    assert_eq!(camera(&obj), camera(&gltf));
    assert_eq!(obj.light, gltf.light);
    let (reference, runs) = render(&obj, &["afsm", "raytrace"]);
    assert_same_visibility("obj-cards-afsm", &runs[0], &reference);
    assert_same_visibility("obj-cards-raytrace", &runs[1], &reference);
    let (gltf_reference, _) = render(&gltf, &[]);
    assert_same_visibility("obj-cards-vs-gltf", &reference, &gltf_reference);

    // The cut-outs matter: cards kept whole cast more shadow.
    let whole = load(
        "masked/cards.obj",
        &LoadOptions {
            obj_kd_alpha: false,
            ..Default::default()
        },
    );
    let (whole_reference, _) = render(&whole, &[]);
    let dark = |v: &Visibility| (0..v.value.len()).filter(|&k| v.luminance(k) < 0.5).count();
    assert!(
        dark(&whole_reference) > dark(&reference) + 100,
        "{} shadowed pixels with the map_Kd card whole, {} cut out",
        dark(&whole_reference),
        dark(&reference)
    );
}

#[test]
fn a_z_up_file_turned_up_is_its_y_up_twin() {
    let y_up = load("masked/cards.obj", &LoadOptions::default());
    let z = LoadOptions {
        up: UpAxis::Z,
        ..Default::default()
    };
    let z_up = load("masked/cards-zup.obj", &z);
    assert_eq!(z_up.v0, y_up.v0);
    assert_eq!(z_up.v1, y_up.v1);
    assert_eq!(z_up.v2, y_up.v2);
    assert_eq!(z_up.bounds.min, y_up.bounds.min);
    assert_eq!(z_up.bounds.max, y_up.bounds.max);
    assert_eq!(camera(&z_up), camera(&y_up));
    assert_eq!(z_up.light, y_up.light);
    let (a, _) = render(&y_up, &[]);
    let (b, runs) = render(&z_up, &["afsm"]);
    assert_same_visibility("obj-cards-z-up", &b, &a);
    assert_same_visibility("obj-cards-z-up-afsm", &runs[0], &b);

    // Loaded without the turn, the file stands on its edge: its floor is upright.
    let unturned = load("masked/cards-zup.obj", &LoadOptions::default());
    let extent = unturned.bounds.max - unturned.bounds.min;
    let upright = y_up.bounds.max - y_up.bounds.min;
    assert!(extent.y > upright.y * 2.0, "{extent} vs {upright}");
}

#[test]
fn up_is_refused_for_built_in_and_toml_scenes() {
    let z = LoadOptions {
        up: UpAxis::Z,
        ..Default::default()
    };
    let e = shadowlab::scene::load_with("bunny", &Default::default(), &z).unwrap_err();
    assert!(e.is_bad_input() && e.to_string().contains("--up z"), "{e}");
}

#[test]
fn a_toml_mesh_turns_up_by_its_up_key_and_keeps_its_cut_outs() {
    let dir = support::scratch("toml-up");
    let masked = data("masked");
    let toml = |extra: &str| {
        format!(
            "[[mesh]]\nfile = {:?}\nup = \"z\"\n{extra}",
            masked.join("cards-zup.obj").to_str().unwrap()
        )
    };
    let path = dir.join("scene.toml");
    let access = shadowlab::files::Access::anywhere();
    std::fs::write(&path, toml("")).unwrap();
    let turned = shadowlab::scene::toml::load_with(&path, &access).unwrap();
    let y_up = shadowlab::scene::obj::load(&masked.join("cards.obj")).unwrap();
    assert_eq!(turned.v0, y_up.v0);
    assert_eq!(turned.uv, y_up.uv);
    assert!(material(&turned, "leaf_kd").alpha_mask.is_some());
    std::fs::write(&path, toml("obj_kd_alpha = false\n")).unwrap();
    let whole = shadowlab::scene::toml::load_with(&path, &access).unwrap();
    assert!(material(&whole, "leaf_kd").alpha_mask.is_none());
    assert!(material(&whole, "leaf_d").alpha_mask.is_some());
    std::fs::write(&path, toml("").replace("\"z\"", "\"up\"")).unwrap();
    let e = shadowlab::scene::toml::load_with(&path, &access).unwrap_err();
    assert!(
        e.to_string().contains("`up` = \"up\" is not an axis"),
        "{e}"
    );
}
