//! Stage `fit` and the soft variants' blocker search: the library's own, over the maps the
//! GPU drew, read back, so the GPU normalizes each map over the depth range its CPU twin
//! would fit to those maps and widens each pixel's filter as its twin would.

use super::Codec;
use shadowlab::light::{cube_face, Light, LightView};
use shadowlab::raster::DepthBuffer;
use shadowlab::techniques::filtering::blocker_search::SoftSearch;
use shadowlab::techniques::filtering::{DepthRange, FilterSettings, ReceiverDepths};
use shadowlab::techniques::{Frame, Stats};

/// The light view a point is looked up in (the library's choice).
fn view_index(light: &Light, p: shadowlab::math::Vec3) -> usize {
    match *light {
        Light::Point { position } => cube_face(p - position),
        _ => 0,
    }
}

/// Each view's fitted depth range (the library's `DepthRange::fitted` over its
/// `ReceiverDepths`), recording the stage `fit` and the counter `shadowable_share`.
pub(super) fn ranges(
    frame: &Frame,
    views: &[LightView],
    maps: &[DepthBuffer],
    codec: &Codec,
    stats: &mut Stats,
) -> Vec<DepthRange> {
    let receivers = stats.stage("fit", || {
        ReceiverDepths::of_frame(frame, views, maps, &codec.settings)
    });
    let (count, shadowable) = receivers
        .iter()
        .fold((0, 0), |(c, s), r| (c + r.count, s + r.shadowable));
    stats.count("shadowable_share", shadowable as f64 / count.max(1) as f64);
    maps.iter()
        .zip(views)
        .zip(&receivers)
        .map(|((m, v), r)| DepthRange::fitted(m, v, r, codec.span))
        .collect()
}

/// For the soft variants under an area light, each pixel's penumbra footprint side in map
/// coordinates (the library's blocker search; −1 where no blocker is found, so the pixel is
/// lit; 0 where the light does not reach). `None` when the filter is not widened.
pub(super) fn soft_widths(
    frame: &Frame,
    settings: &FilterSettings,
    views: &[LightView],
    maps: &[DepthBuffer],
) -> Option<Vec<f32>> {
    let search = SoftSearch::new(frame, settings, views, maps)?;
    let view = frame.view;
    Some(
        (0..view.triangle.len())
            .map(|k| {
                if !frame.receiver_lit(k) {
                    return 0.0;
                }
                let p = view.position[k];
                let i = view_index(frame.light, p);
                let s = views[i].project(p);
                match search.footprint(frame, k, i, &s) {
                    Some(fp) => fp.dx.x,
                    None => -1.0,
                }
            })
            .collect(),
    )
}
