//! Turning a shadow term into pictures: Lambert shading with an ambient term, error
//! images, and the float EXR of the raw visibility.

use crate::error::{Error, Result};
use crate::frame::{luminance, Visibility};
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::picture::{save_image, to_srgb8};
pub use crate::picture::{save_png, RgbImage};
use crate::scene::Scene;
use crate::view::{ViewLayers, ViewSamples};
use image::{ImageBuffer, Rgb, Rgba};
use std::path::Path;

/// Share of the albedo lit by ambient light, so shadowed surfaces stay readable.
pub const AMBIENT: f32 = 0.25;
/// Colour of pixels no surface covers.
pub const BACKGROUND: Vec3 = vec3(0.18, 0.2, 0.24);

/// The shaded colour of one surface sample: `albedo · (ambient + (1 − ambient) ·
/// max(0, n·l) · visibility)`.
fn surface_colour(albedo: Vec3, p: Vec3, n: Vec3, light: &Light, vis: Vec3) -> Vec3 {
    let (l, _) = light.shadow_ray(p);
    let direct = if light.illuminates(p, n) {
        n.dot(l).max(0.0)
    } else {
        0.0
    };
    albedo * (AMBIENT + (1.0 - AMBIENT) * direct * vis)
}

/// Shades a frame: `albedo · (ambient + (1 − ambient) · max(0, n·l) · visibility)`.
pub fn shade(scene: &Scene, view: &ViewSamples, light: &Light, vis: &Visibility) -> RgbImage {
    let (w, h) = (view.width, view.height);
    ImageBuffer::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        if !view.covered(k) {
            return Rgb(to_srgb8(BACKGROUND));
        }
        let albedo = scene.material_of(view.triangle[k] as usize).color;
        Rgb(to_srgb8(surface_colour(
            albedo,
            view.position[k],
            view.normal[k],
            light,
            vis.value[k],
        )))
    })
}

/// Shades a frame with the layers behind its semi-transparent surfaces composited front to
/// back: every surface of a pixel (the nearest one, then its layers) is shaded as in
/// [`shade`] with its own shadow term, weighted by its opacity `1 − T` (per channel, `T`
/// the material's transmittance) times the product of the transmittances in front of it;
/// what passes the last surface shows the background.
pub fn shade_layers(
    scene: &Scene,
    view: &ViewSamples,
    layers: &ViewLayers,
    light: &Light,
    vis: &Visibility,
    layer_vis: &[Vec3],
) -> RgbImage {
    let (w, h) = (view.width, view.height);
    ImageBuffer::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        if !view.covered(k) {
            return Rgb(to_srgb8(BACKGROUND));
        }
        let surfaces = std::iter::once((
            view.triangle[k],
            view.position[k],
            view.normal[k],
            vis.value[k],
        ))
        .chain(layers.of_pixel(k).map(|i| {
            (
                layers.triangle[i],
                layers.position[i],
                layers.normal[i],
                layer_vis[i],
            )
        }));
        let mut colour = Vec3::ZERO;
        let mut through = Vec3::ONE;
        for (id, p, n, v) in surfaces {
            let m = scene.material_of(id as usize);
            colour +=
                through * (Vec3::ONE - m.transmittance) * surface_colour(m.color, p, n, light, v);
            through *= m.transmittance;
        }
        Rgb(to_srgb8(colour + through * BACKGROUND))
    })
}

/// A diverging error picture: blue where the technique is darker than the reference, red
/// where it is lighter, black where they agree; uncovered pixels grey.
pub fn error_image(view: &ViewSamples, vis: &Visibility, reference: &Visibility) -> RgbImage {
    let (w, h) = (view.width, view.height);
    ImageBuffer::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        if !view.covered(k) {
            return Rgb([40, 40, 40]);
        }
        let d = luminance(vis.value[k]) - luminance(reference.value[k]);
        let m = (d.abs().sqrt() * 255.0) as u8;
        if d > 0.0 {
            Rgb([m, 0, 0])
        } else {
            Rgb([0, m / 3, m])
        }
    })
}

/// A reference's per-pixel standard error on the error images' scale (brightness ∝
/// √error), in yellow; uncovered pixels grey.
pub fn std_error_image(view: &ViewSamples, std_error: &[f32]) -> RgbImage {
    let (w, h) = (view.width, view.height);
    ImageBuffer::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        if !view.covered(k) {
            return Rgb([40, 40, 40]);
        }
        let m = (std_error[k].max(0.0).sqrt().min(1.0) * 255.0) as u8;
        Rgb([m, m, 0])
    })
}

/// Writes the raw shadow term as a float32 RGBA OpenEXR: R, G, B = transmittance towards
/// the light (1 = lit), A = coverage (1 where a surface covers the pixel centre).
pub fn write_visibility_exr(path: &Path, view: &ViewSamples, vis: &Visibility) -> Result<()> {
    let (w, h) = (view.width, view.height);
    let img: ImageBuffer<Rgba<f32>, Vec<f32>> = ImageBuffer::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        let v = vis.value[k];
        Rgba([v.x, v.y, v.z, if view.covered(k) { 1.0 } else { 0.0 }])
    });
    save_image(&img, image::ImageFormat::OpenExr, path)
}

/// Reads a visibility EXR written by [`write_visibility_exr`]: the shadow term and the
/// coverage mask.
///
/// The file is read as the loaders read theirs ([`crate::files::read_sniffed`]): a regular
/// file only, refused unless it starts with the OpenEXR magic number, and its size read
/// from its header and checked against the image limits and the memory limit before it
/// is decoded.
pub fn read_visibility_exr(path: &Path) -> Result<(Visibility, Vec<bool>)> {
    const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    let bytes = crate::files::read_sniffed(path, crate::files::MAX_FILE_BYTES, |head| {
        if head.starts_with(&EXR_MAGIC) {
            Ok(())
        } else {
            Err("not an OpenEXR image (it does not start with the EXR magic number)".into())
        }
    })
    .map_err(|e| match e {
        crate::files::Unread::File(why) => Error::io(path, why),
        crate::files::Unread::Format(what) => Error::format(path, what),
    })?;
    let not_exr =
        |e: image::ImageError| Error::format(path, format!("not a readable EXR image ({e})"));
    let reader = || {
        image::ImageReader::with_format(
            std::io::Cursor::new(&bytes[..]),
            image::ImageFormat::OpenExr,
        )
    };
    let (w, h) = reader().into_dimensions().map_err(not_exr)?;
    let side = crate::camera::MAX_IMAGE_SIDE;
    if w == 0 || h == 0 || w > side || h > side {
        return Err(Error::Limit(format!(
            "{}: its size {w}x{h} is outside 1..={side} pixels a side",
            path.display()
        )));
    }
    // The decoded RGBA f32 image and the two arrays made of it.
    let texels = w as u64 * h as u64;
    crate::limits::check_bytes(
        || format!("{}: its {w}x{h} pixels", path.display()),
        texels * 33,
    )?;
    let mut reader = reader();
    let mut lim = image::Limits::default();
    lim.max_image_width = Some(side);
    lim.max_image_height = Some(side);
    lim.max_alloc = Some(texels * 16);
    reader.limits(lim);
    let img = reader.decode().map_err(not_exr)?.into_rgba32f();
    let (w, h) = img.dimensions();
    let mut value = Vec::with_capacity((w * h) as usize);
    let mut covered = Vec::with_capacity((w * h) as usize);
    for p in img.pixels() {
        value.push(vec3(p[0], p[1], p[2]));
        covered.push(p[3] > 0.5);
    }
    Ok((
        Visibility {
            width: w,
            height: h,
            value,
        },
        covered,
    ))
}
