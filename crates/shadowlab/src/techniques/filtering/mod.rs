//! Texture filtering for pre-filtered shadow maps: the software equivalent of a GPU's
//! render-target blur, automatic mip-map generation and tri-linear / anisotropic texture
//! look-ups, shared by `csm`, `vsm`, `evsm` and `msm`. It is the pre-filtering stage of the
//! convolution shadow map paper (Annen et al. 2007, Section 4: "we perform mip-mapping as
//! well as blurring" of the basis images, then read them with "tri-linear and anisotropic
//! filtering"), which the moment-based maps share.
//!
//! The chain, in the order a frame runs it ([`prefiltered`]): render the light's depth
//! maps, fit each map's depth interval to the receivers ([`receivers`], [`depth_range`]),
//! encode each texel into the technique's values (its basis or moments, stored as a
//! [`Texture`], [`texture`]), blur it ([`blur`](mod@blur)), build the mip chain ([`mip`]), and per pixel take
//! the filtered values under the pixel's footprint in the map ([`footprint`], [`lookup`])
//! and hand them to the technique's test. [`settings`] holds the three parameters the
//! filtered techniques share.
//!
//! A [`Texture`] holds `channels` values per texel, interleaved, in a [`Channel`] format:
//! `u8` (8-bit unsigned normalized, stored as raw codes 0..=255, rounded on every write as
//! a GPU render target is) or `f32`. Filtering is linear in the stored codes, so a caller
//! that encodes linearly (`code = a·value + b`) decodes the filtered code the same way.
//!
//! - [`blur()`]: a separable binomial (discrete Gaussian) kernel of odd side `n`, clamp-to-edge,
//!   each pass written back in the texture's format like a two-pass GPU blur.
//! - [`MipChain::build`]: a full chain down to 1×1, each level the box-filtered previous
//!   level (2×2 average for even sides, area-weighted taps for odd sides), quantized like
//!   `glGenerateMipmap` on an 8-bit texture.
//! - [`MipChain::sample`]: bilinear (level 0 only), tri-linear (level of detail
//!   λ = log2 of the longer screen-space derivative in texels, blended between the two
//!   nearest levels) or anisotropic filtering as `EXT_texture_filter_anisotropic`
//!   describes it: `N = min(⌈Pmax/Pmin⌉, max_aniso)` tri-linear probes spread along the
//!   major axis of the footprint at λ = log2(Pmax/N). Addressing clamps to the edge and
//!   texel centres lie at `(i + 0.5) / side`.
//! - [`light_footprint`]: the screen-space derivatives of light-map coordinates, taken by
//!   projecting the camera pass's `position ± dpdx` and `position ± dpdy` into the light
//!   view and differencing them. For an orthographic light this is exactly the projection
//!   of the world-space step to the next pixel (the GPU's `ddx/ddy`); for a perspective
//!   light the symmetric difference cancels the projection's curvature to first order.
//!
//! - [`ReceiverDepths`] and [`DepthRange::fitted`]: the depth interval a map is normalized
//!   over, fitted to the receivers that may be shadowed (some texel under their filter
//!   support, found with a [`MinPyramid`], is nearer than their own tangent plane there).
//!
//! Invariants: every pass is a pure function of its input, computed per row in parallel
//! and collected in order, so results are bit-identical for any thread count; filter
//! weights of every look-up sum to one, so a constant texture samples to that constant.
//! Known departures from hardware: GPUs approximate λ and the anisotropic probe placement
//! with reduced-precision arithmetic and vendor-specific footprints; here both are exact.

pub mod blocker_search;
pub mod blur;
pub mod depth_range;
pub mod footprint;
pub mod lookup;
pub mod mip;
pub mod prefiltered;
pub mod receivers;
pub mod settings;
pub mod texture;

pub use blur::{binomial_weights, blur, check_blur, parse_blur, MAX_BLUR};
pub use depth_range::{DepthRange, FITTED_RANGE_SLACK, MIN_RANGE_RELATIVE};
pub use footprint::{light_footprint, Footprint};
pub use lookup::{level_of_detail, Filter, Lod, DEFAULT_ANISOTROPY, MAX_ANISOTROPY};
pub use mip::MipChain;
pub use prefiltered::{
    check_map_size, texel_rows, FilteredMaps, MapLayout, MAX_FILTERED_MAP_BYTES,
};
pub use receivers::{MinPyramid, ReceiverDepths, MAX_RECEIVER_SLOPE};
pub use settings::FilterSettings;
pub(crate) use texture::with_channels;
pub use texture::{fast_ceil, fast_floor, Channel, Texture};

use crate::light::{cube_face, Light};
use crate::math::Vec3;

/// The number of light views (and maps) a light needs: six cube faces for a point light,
/// one otherwise.
pub fn view_count(light: &Light) -> usize {
    if matches!(light, Light::Point { .. }) {
        6
    } else {
        1
    }
}

/// The light view a point `p` is looked up in: for a point light the cube face its
/// direction from the light selects, else the only view.
#[inline]
fn light_view_index(light: &Light, p: Vec3) -> usize {
    match *light {
        Light::Point { position } => cube_face(p - position),
        _ => 0,
    }
}

/// Pixels per parallel work item of the per-pixel passes ([`ReceiverDepths::of_frame`],
/// [`FilteredMaps::lookup`]).
const PIXEL_CHUNK: usize = 1024;
