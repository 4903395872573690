//! The technique's own images in the panel: those it writes as `--dump` does, as egui's
//! textures; and the depth maps of a technique drawn on the device (`gpu:sm`, `gpu:pcf`,
//! `gpu:psm`, `gpu:lispsm`, `gpu:cascaded`, `gpu:pcss`),
//! the layer chosen converted there into a grey picture (near dark, far white) of at most
//! [`SIDE`] texels a side.

use super::app::App;
use super::session::Technique;
use super::window::Screen;
use anyhow::Result;
use shadowlab_gpu::compute::pipeline;
use shadowlab_gpu::shader::Stage;
use shadowlab_gpu::transfer::uniform;

const MAP_VIEW: Stage = Stage {
    name: "view/map_view.wgsl",
    common: &[],
    source: include_str!("map_view.wgsl"),
};

/// The picture's largest side.
pub const SIDE: u32 = 512;

/// `Pick` of `map_view.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Pick {
    layer: u32,
    side: u32,
    pad: [u32; 2],
}

/// A layer of the maps as egui's texture.
pub struct MapView {
    /// The layer shown.
    pub layer: u32,
    /// egui's texture.
    pub id: egui::TextureId,
    /// The picture's side.
    pub side: u32,
    picture: wgpu::Texture,
}

/// The layers of `maps`.
pub fn layers(maps: &wgpu::Texture) -> u32 {
    maps.depth_or_array_layers()
}

/// Draws layer `layer` of `maps` into `old`'s picture (or a new one) for egui.
pub fn show(
    screen: &mut Screen,
    maps: &wgpu::Texture,
    layer: u32,
    old: Option<MapView>,
) -> Result<MapView> {
    let gpu = screen.gpu.clone();
    let side = maps.width().min(SIDE);
    let (picture, id) = match old {
        Some(o) if o.side == side => (o.picture, Some(o.id)),
        Some(o) => {
            screen.free_texture(o.id);
            (new_picture(&gpu, side), None)
        }
        None => (new_picture(&gpu, side), None),
    };
    let pipe = pipeline(&gpu, &MAP_VIEW, "main");
    let pick = uniform(
        &gpu,
        "the map layer shown",
        &Pick {
            layer,
            side: maps.width(),
            pad: [0; 2],
        },
    );
    let map_view = maps.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let out = picture.create_view(&Default::default());
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("map view"),
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&map_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&out),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: pick.as_entire_binding(),
            },
        ],
    });
    gpu.stage("view", "map view", || {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
        }
        gpu.queue.submit([encoder.finish()]);
    })?;
    let id = match id {
        Some(id) => id,
        None => screen.native_texture(&picture.create_view(&Default::default())),
    };
    Ok(MapView {
        layer,
        id,
        side,
        picture,
    })
}

fn new_picture(gpu: &shadowlab_gpu::device::Gpu, side: u32) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("map view"),
        size: wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    })
}

impl App<'_> {
    /// The technique's image chosen, as egui's texture.
    pub(super) fn show_dump(&mut self) {
        let (Some(d), Some(w)) = (&self.drawn, &self.window) else {
            return;
        };
        let chosen = self.session.show.dump;
        if chosen.is_some_and(|i| i >= d.dumps.len()) {
            self.session.show.dump = None;
            if d.dumps.is_empty() {
                self.session.status = format!("{} shows no images", self.session.name);
            }
        }
        self.dump = self.session.show.dump.and_then(|i| {
            let (name, img) = d.dumps.get(i)?;
            let size = [img.width() as usize, img.height() as usize];
            let colour = egui::ColorImage::from_rgb(size, img.as_raw());
            let t = w
                .egui
                .load_texture(name, colour, egui::TextureOptions::NEAREST);
            Some((i, t, [size[0] as f32, size[1] as f32]))
        });
    }

    /// The layer of the technique's depth maps chosen, as egui's texture.
    pub(super) fn show_map(&mut self) {
        let maps = match (&self.session.technique, &self.on_device) {
            (Technique::Device(t), Some(_)) => t.depth_maps(),
            _ => None,
        };
        self.map_layers = maps.map_or(0, layers);
        let Some(w) = &mut self.window else {
            return;
        };
        let Some(maps) = maps else {
            if let Some(v) = self.map_view.take() {
                w.free_texture(v.id);
            }
            return;
        };
        match self.session.show.map.filter(|l| *l < self.map_layers) {
            Some(l) => match show(w, maps, l, self.map_view.take()) {
                Ok(v) => self.map_view = Some(v),
                Err(e) => self.session.status = crate::failure::sentence(&e),
            },
            None => {
                if let Some(v) = self.map_view.take() {
                    w.free_texture(v.id);
                }
            }
        }
    }
}
