//! # shadowlab
//!
//! Shadow rendering algorithms from five papers — alias-free shadow maps (Aila & Laine
//! 2004), adaptive shadow maps (Fernando et al. 2001), sub-pixel anti-aliased shadow maps
//! (Pan et al. 2009), perspective shadow maps (Stamminger & Drettakis 2002) and convolution
//! shadow maps (Annen et al. 2007) — beside the baselines they are measured against
//! (standard shadow maps, PCF, variance shadow maps), all judged against a ray-traced
//! reference on the same camera pass.
//!
//! The data flow of one frame:
//!
//! ```text
//! Scene ──camera pass (raster)──▶ ViewSamples ──ShadowTechnique──▶ Visibility + Stats
//!                                                    │
//!                         shade → image   ◀──────────┴──────▶ compare with the reference
//! ```
//!
//! A minimal use, without the command line:
//!
//! ```
//! use shadowlab::prelude::*;
//! let scene = Scene::from_triangles(
//!     vec![
//!         // a ground quad and a small floating square above it
//!         [vec3(-2.0, 0.0, -2.0), vec3(2.0, 0.0, 2.0), vec3(2.0, 0.0, -2.0)],
//!         [vec3(-2.0, 0.0, -2.0), vec3(-2.0, 0.0, 2.0), vec3(2.0, 0.0, 2.0)],
//!         [vec3(-0.5, 1.0, -0.5), vec3(0.5, 1.0, 0.5), vec3(0.5, 1.0, -0.5)],
//!         [vec3(-0.5, 1.0, -0.5), vec3(-0.5, 1.0, 0.5), vec3(0.5, 1.0, 0.5)],
//!     ],
//!     Material::default(),
//! )
//! .unwrap();
//! let camera = Camera::look_at(vec3(0.0, 4.0, 5.0), Vec3::ZERO, 45.0, 64, 48);
//! let light = Light::Directional { to_light: vec3(0.2, 1.0, 0.1).normalize() };
//! let view = ViewSamples::render(&scene, &camera);
//! let frame = Frame::new(&scene, &camera, &light, &view);
//! let mut technique = shadowlab::techniques::create("sm").unwrap();
//! let shadows = technique.render(&frame).unwrap();
//! assert_eq!(shadows.visibility.width, 64);
//! ```
// Unsafe code is allowed in three places only: the Embree bindings (an optional feature),
// the calls into functions compiled for an instruction set the processor was checked for,
// and the memory limits (the C library's rlimit and the global allocator wrapper).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod area_light;
pub mod auto_light;
pub mod bvh;
pub mod camera;
pub mod compare;
#[cfg(feature = "embree")]
#[allow(unsafe_code)]
pub mod embree;
pub mod error;
pub mod files;
pub mod frame;
pub mod gbuffer;
pub mod light;
#[allow(unsafe_code)]
pub mod limits;
pub mod math;
pub mod multi_light;
pub mod picture;
pub mod points;
pub mod raster;
pub mod reference;
pub mod sampling;
pub mod scene;
pub mod shade;
pub mod soft_reference;
pub mod techniques;
pub mod temporal;
pub mod view;

pub use error::{Error, Result};

/// The types most programs need, for `use shadowlab::prelude::*`.
pub mod prelude {
    pub use crate::camera::Camera;
    pub use crate::error::{Error, Result};
    pub use crate::frame::{Frame, Stats, Visibility};
    pub use crate::light::Light;
    pub use crate::math::{vec3, Vec3};
    pub use crate::scene::{Material, Scene};
    pub use crate::techniques::{ShadowTechnique, Shadows};
    pub use crate::view::ViewSamples;
}
