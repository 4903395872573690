//! The chain of a pre-filtered shadow map on one frame (Annen et al. 2007, Section 4.1),
//! shared by `csm`, `vsm`, `evsm` and `msm`: render the light's depth maps, fit their depth
//! intervals to the receivers, encode every texel into the technique's values (basis
//! images or moments), blur, mip-map, then per pixel look the filtered values up under its
//! footprint and hand them to the technique's test ([`FilteredMaps::shade`]).

use super::super::shadow_map::render_light_maps;
use super::blocker_search::{wider, SoftSearch};
use super::depth_range::DepthRange;
use super::footprint::light_footprint;
use super::mip::MipChain;
use super::receivers::ReceiverDepths;
use super::settings::FilterSettings;
use super::texture::{chans, with_channels, Channel, Texture};
use super::{light_view_index, view_count, PIXEL_CHUNK};
use crate::error::{Error, Result};
use crate::frame::{Frame, Stats};
use crate::light::LightView;
use crate::math::Vec3;
use crate::picture::RgbImage;
use crate::raster::DepthBuffer;
use rayon::prelude::*;

/// Bytes a filtered map (all views, all levels) may take before a render is refused.
pub const MAX_FILTERED_MAP_BYTES: u64 = 3 << 30;

/// Refuses a filtered map larger than [`MAX_FILTERED_MAP_BYTES`] before anything is
/// allocated: `views` maps of `side²` texels with `channels` values of `bytes` each, plus
/// a third for the mip levels.
pub fn check_map_size(
    technique: &str,
    views: usize,
    side: u32,
    channels: usize,
    bytes: usize,
) -> Result<()> {
    let total = views as u64 * (side as u64).pow(2) * channels as u64 * bytes as u64 * 4 / 3;
    if total > MAX_FILTERED_MAP_BYTES {
        return Err(Error::Limit(format!(
            "{technique}: {views} filtered map(s) of {side}² texels × {channels} channels would take {} MiB, more than {} MiB; lower --param resolution (or m)",
            total >> 20,
            MAX_FILTERED_MAP_BYTES >> 20
        )));
    }
    crate::limits::check_bytes(
        || format!("{technique}: {views} filtered map(s) of {side}² texels × {channels} channels"),
        total,
    )
}

/// What the pre-filtered maps of a technique hold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapLayout {
    /// The technique's name, for errors.
    pub technique: &'static str,
    /// Map side in texels.
    pub resolution: u32,
    /// Values per texel.
    pub channels: usize,
    /// The normalized depth of the farthest texel (see [`DepthRange`]).
    pub span: f32,
}

/// The row encoder of [`FilteredMaps::build_rows`] that a per-texel encoder `encode(map,
/// range, x, y, out)` gives: each texel's values are computed into a row of numbers, which
/// is then stored in the format `T` with [`Channel::store_row`].
pub fn texel_rows<'e, T: Channel>(
    channels: usize,
    encode: &'e (impl Fn(&DepthBuffer, &DepthRange, u32, u32, &mut [f32]) + Sync),
    range: DepthRange,
) -> impl Fn(&DepthBuffer, u32, &mut [T]) + Sync + 'e {
    move |m: &DepthBuffer, y: u32, row: &mut [T]| {
        let mut v = vec![0.0f32; row.len()];
        for (x, texel) in v.chunks_exact_mut(channels).enumerate() {
            encode(m, &range, x as u32, y, texel);
        }
        T::store_row(&v, row);
    }
}

/// Pre-filtered light maps of one frame: per light view, the encoded map with its mip
/// chain and the depth range it was normalized with.
#[derive(Clone, Debug)]
pub struct FilteredMaps<T> {
    /// The light views (one, or six cube faces).
    pub views: Vec<LightView>,
    /// Encoded, blurred and mip-mapped map of each view.
    pub chains: Vec<MipChain<T>>,
    /// Depth normalization of each view.
    pub ranges: Vec<DepthRange>,
    /// Bytes of the depth maps the chains were computed from.
    pub depth_bytes: u64,
    /// With soft filtering, each view's depth map, kept for the blocker search.
    pub depth_maps: Vec<DepthBuffer>,
}

impl<T: Channel> FilteredMaps<T> {
    /// The whole chain of a pre-filtered technique on one frame: refuses maps larger than
    /// [`check_map_size`] allows, builds them ([`Self::build_rows`]), looks every pixel up
    /// ([`Self::lookup`]) and records the maps' memory (`memory_bytes` and the counter
    /// `depth_map_bytes`). Returns the maps and the shadow term of every pixel.
    pub fn shade<E: Fn(&DepthBuffer, u32, &mut [T]) + Sync>(
        frame: &Frame,
        layout: &MapLayout,
        settings: &FilterSettings,
        stats: &mut Stats,
        encoder: impl Fn(&DepthRange) -> E,
        test: impl Fn(f32, &[f32]) -> f32 + Sync,
    ) -> Result<(Self, Vec<Vec3>)> {
        let views = view_count(frame.light);
        let (res, ch) = (layout.resolution, layout.channels);
        check_map_size(layout.technique, views, res, ch, T::BYTES)?;
        let maps = Self::build_rows(frame, layout, settings, stats, encoder);
        let value = maps.lookup(frame, settings, stats, test);
        stats.memory_bytes = maps.memory_bytes();
        stats.count("depth_map_bytes", maps.depth_bytes as f64);
        Ok((maps, value))
    }

    /// [`Self::shade`] with a per-texel encoder `encode(map, range, x, y, out)` (see
    /// [`texel_rows`]).
    pub fn shade_texels(
        frame: &Frame,
        layout: &MapLayout,
        settings: &FilterSettings,
        stats: &mut Stats,
        encode: impl Fn(&DepthBuffer, &DepthRange, u32, u32, &mut [f32]) + Sync,
        test: impl Fn(f32, &[f32]) -> f32 + Sync,
    ) -> Result<(Self, Vec<Vec3>)> {
        let ch = layout.channels;
        let encoder = |r: &DepthRange| texel_rows(ch, &encode, *r);
        Self::shade(frame, layout, settings, stats, encoder, test)
    }

    /// Renders the light's depth maps at the layout's resolution, fits their depth ranges
    /// (`fit_ranges`), encodes them with an encoder of whole rows that stores the
    /// texture's format itself, then blurs and mip-maps as `settings` says; records the
    /// stages `shadow_map`, `fit`, `encode`, `blur` and `mipmap` in `stats`.
    /// `encoder(range)` is called once per view, inside the `encode` stage (so it may
    /// prepare tables for that view's depth range), and returns `encode(map, y, row)`, which
    /// writes the `width × channels` stored values of row `y` into `row` (which holds
    /// `T::default()` before the call).
    pub fn build_rows<E: Fn(&DepthBuffer, u32, &mut [T]) + Sync>(
        frame: &Frame,
        layout: &MapLayout,
        settings: &FilterSettings,
        stats: &mut Stats,
        encoder: impl Fn(&DepthRange) -> E,
    ) -> Self {
        let maps = stats.stage("shadow_map", || render_light_maps(frame, layout.resolution));
        let ranges = fit_ranges(frame, &maps.views, &maps.maps, layout.span, settings, stats);
        let encoded: Vec<Texture<T>> = stats.stage("encode", || {
            maps.maps
                .iter()
                .zip(&ranges)
                .map(|(m, r)| {
                    let encode = encoder(r);
                    Texture::from_stored_rows(m.width, m.height, layout.channels, |y, row| {
                        encode(m, y, row)
                    })
                })
                .collect()
        });
        let blurred: Vec<Texture<T>> = if settings.blur > 1 {
            stats.stage("blur", || {
                encoded.into_iter().map(|t| settings.blurred(t)).collect()
            })
        } else {
            encoded
        };
        let chains = stats.stage("mipmap", || {
            blurred.into_iter().map(|t| settings.mip_chain(t)).collect()
        });
        let depth_bytes = maps.memory_bytes();
        let depth_maps = if settings.soft { maps.maps } else { Vec::new() };
        FilteredMaps {
            views: maps.views,
            chains,
            ranges,
            depth_bytes,
            depth_maps,
        }
    }

    /// Levels of the first view's mip chain (0 without views).
    pub fn mip_levels(&self) -> usize {
        self.chains.first().map_or(0, |c| c.levels.len())
    }

    /// Hands level 0 of each view's map to the frame's dump as the picture `file(i)` for
    /// view `i`, each texel coloured `colour(texel)` (made only when the frame is dumping).
    pub fn dump_level0(
        &self,
        frame: &Frame,
        file: impl Fn(usize) -> String,
        colour: impl Fn(&[T]) -> [u8; 3],
    ) -> Result<()> {
        for (i, c) in self.chains.iter().enumerate() {
            let t = &c.levels[0];
            frame.dump_image(&file(i), || {
                RgbImage::from_fn(t.width, t.height, |x, y| image::Rgb(colour(t.texel(x, y))))
            })?;
        }
        Ok(())
    }

    /// Bytes held by the filtered maps (every level of every view), and the depth maps
    /// soft filtering keeps.
    pub fn memory_bytes(&self) -> u64 {
        let kept: u64 = self
            .depth_maps
            .iter()
            .map(|m| m.depth.len() as u64 * 4)
            .sum();
        self.chains.iter().map(|c| c.memory_bytes()).sum::<u64>() + kept
    }

    /// The shadow term of every pixel of `frame`: for each pixel the light can reach, the
    /// filtered values at its light-map position are passed, with its normalized light
    /// depth, to `test(d, values)`. Pixels the light cannot reach get 0, uncovered ones 1.
    /// Records the stage `lookup` and the counters `mean_probes` and `minified_share`.
    pub fn lookup(
        &self,
        frame: &Frame,
        settings: &FilterSettings,
        stats: &mut Stats,
        test: impl Fn(f32, &[f32]) -> f32 + Sync,
    ) -> Vec<Vec3> {
        let ch = self.chains.first().map_or(1, |c| c.channels());
        let (values, codes) = stats.stage("lookup", || {
            with_channels!(ch, lookup_n::<T>, (self, frame, settings, &test))
        });
        // Counters summed in pixel order, so they do not depend on the thread count.
        let (mut lit, mut probes, mut minified) = (0u64, 0u64, 0u64);
        for &c in &codes {
            if c & 0x7f > 0 {
                lit += 1;
                probes += (c & 0x7f) as u64;
                minified += (c >> 7) as u64;
            }
        }
        let lit = lit.max(1) as f64;
        stats.count("mean_probes", probes as f64 / lit);
        stats.count("minified_share", minified as f64 / lit);
        values
    }
}

/// The depth range of each view's map, fitted to the receivers of `frame` (the stage `fit`,
/// see [`DepthRange::fitted`]), with the counters `shadowable_share` and, for the first
/// view, `fit_near`, `fit_far`, `receivers_near` and `receivers_far`.
fn fit_ranges(
    frame: &Frame,
    views: &[LightView],
    maps: &[DepthBuffer],
    span: f32,
    settings: &FilterSettings,
    stats: &mut Stats,
) -> Vec<DepthRange> {
    let receivers = stats.stage("fit", || {
        ReceiverDepths::of_frame(frame, views, maps, settings)
    });
    let (count, shadowable) = receivers
        .iter()
        .fold((0, 0), |(c, s), r| (c + r.count, s + r.shadowable));
    stats.count("shadowable_share", shadowable as f64 / count.max(1) as f64);
    if let Some(r) = receivers.first() {
        stats.count("fit_near", r.shadowable_near as f64);
        stats.count("fit_far", r.shadowable_far as f64);
        stats.count("receivers_near", r.near as f64);
        stats.count("receivers_far", r.far as f64);
    }
    maps.iter()
        .zip(views)
        .zip(&receivers)
        .map(|((m, v), r)| DepthRange::fitted(m, v, r, span))
        .collect()
}

/// The per-pixel look-ups of [`FilteredMaps::lookup`] for maps of `N` channels: each
/// pixel's shadow term and, in a second vector, a byte packing its probe count (low 7 bits,
/// 0 when the light cannot reach it) and whether it was minified (high bit).
fn lookup_n<T: Channel, const N: usize>(
    maps: &FilteredMaps<T>,
    frame: &Frame,
    settings: &FilterSettings,
    test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
) -> (Vec<Vec3>, Vec<u8>) {
    let view = frame.view;
    let n = (view.width * view.height) as usize;
    let ch = chans::<N>(maps.chains.first().map_or(1, |c| c.channels()));
    let soft = SoftSearch::new(frame, settings, &maps.views, &maps.depth_maps);
    let mut values = vec![Vec3::ONE; n];
    let mut codes = vec![0u8; n];
    values
        .par_chunks_mut(PIXEL_CHUNK)
        .zip(codes.par_chunks_mut(PIXEL_CHUNK))
        .enumerate()
        .for_each_init(
            || vec![0.0f32; ch],
            |buf, (c, (values, codes))| {
                let chunk = LookupChunk {
                    maps,
                    frame,
                    settings,
                    first: c * PIXEL_CHUNK,
                    soft: soft.as_ref(),
                };
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2, checked just above.
                    #[allow(unsafe_code)]
                    unsafe {
                        chunk.run_avx2::<N>(test, buf, values, codes)
                    };
                    return;
                }
                chunk.run::<N>(test, buf, values, codes);
            },
        );
    (values, codes)
}

/// One chunk of pixels of [`lookup_n`], starting at pixel `first`.
struct LookupChunk<'a, 'f, T> {
    maps: &'a FilteredMaps<T>,
    frame: &'a Frame<'f>,
    settings: &'a FilterSettings,
    first: usize,
    soft: Option<&'a SoftSearch<'a>>,
}

impl<T: Channel> LookupChunk<'_, '_, T> {
    /// [`Self::run`] compiled for AVX2: twice the vector width for the same operations, so
    /// the same results (no fused multiply-adds: those would round differently).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2<const N: usize>(
        &self,
        test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
        buf: &mut [f32],
        values: &mut [Vec3],
        codes: &mut [u8],
    ) {
        self.run::<N>(test, buf, values, codes);
    }

    /// The look-ups of the chunk's pixels into `values` and `codes` (see [`lookup_n`]).
    #[inline(always)]
    fn run<const N: usize>(
        &self,
        test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
        buf: &mut [f32],
        values: &mut [Vec3],
        codes: &mut [u8],
    ) {
        let (maps, frame, settings) = (self.maps, self.frame, self.settings);
        let view = frame.view;
        let ch = buf.len();
        for (j, (value, code)) in values.iter_mut().zip(codes).enumerate() {
            let k = self.first + j;
            if !frame.receiver_lit(k) {
                if view.covered(k) {
                    *value = Vec3::ZERO;
                }
                continue;
            }
            let p = view.position[k];
            let i = light_view_index(frame.light, p);
            let lv = &maps.views[i];
            let s = lv.project(p);
            let mut fp = light_footprint(lv, p, view.dpdx[k], view.dpdy[k]);
            if let Some(search) = &self.soft {
                match search.footprint(frame, k, i, &s) {
                    Some(wide) => fp = wider(wide, fp),
                    None => {
                        // No blocker in the light's cone: fully lit.
                        *code = 1;
                        continue;
                    }
                }
            }
            let lod = maps.chains[i].sample_n::<N>(
                s.u,
                s.v,
                &fp,
                settings.filter,
                settings.max_aniso,
                buf,
            );
            let d = maps.ranges[i].normalize(s.depth);
            let minified = u8::from(lod.lambda > 0.0);
            *value = Vec3::splat(test(d, &buf[..ch]));
            *code = lod.probes.clamp(1, 127) as u8 | minified << 7;
        }
    }
}
