//! The depth interval a light map is normalized over, fitted to the receivers that may be
//! shadowed: the "tightly fitted" light frustum the convolution shadow map paper asks for
//! (Annen et al. 2007, Section 5), and the interval the moment maps normalize over too.

use super::receivers::ReceiverDepths;
use crate::light::LightView;
use crate::raster::DepthBuffer;

/// The depth interval a map's texels span, for normalizing linear depths into `[0, span]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthRange {
    /// Nearest rasterized depth.
    pub near: f32,
    /// Farthest rasterized depth.
    pub far: f32,
    /// The normalized value of `far`.
    pub span: f32,
}

impl DepthRange {
    /// The range of the finite depths of `map` (the light view's own range when the map
    /// is empty), normalized to `[0, span]`. Fitting the range to what was rasterized
    /// rather than to the light frustum spends the normalized interval where casters are.
    pub fn of_map(map: &DepthBuffer, view: &LightView, span: f32) -> Self {
        let (mut near, mut far) = (f32::INFINITY, f32::NEG_INFINITY);
        for &d in &map.depth {
            if d.is_finite() {
                near = near.min(d);
                far = far.max(d);
            }
        }
        if near > far {
            (near, far) = (view.near, view.far);
        }
        let far = far.max(near + Self::min_width(near, far));
        DepthRange { near, far, span }
    }

    /// The narrowest interval `[near, far]` may be: [`MIN_RANGE_RELATIVE`] of the larger
    /// depth magnitude (a tiny absolute floor for depths near zero).
    #[inline]
    fn min_width(near: f32, far: f32) -> f32 {
        MIN_RANGE_RELATIVE * near.abs().max(far.abs()).max(f32::MIN_POSITIVE.sqrt())
    }

    /// The depth interval that matters to the receivers this frame shades (see
    /// [`ReceiverDepths`]): from the nearest map texel under the filter support of a receiver
    /// that something may shadow to the farthest such receiver. Normalizing with clamping is
    /// monotone, so the shadow test `z < d` of every such receiver keeps its sign: no texel
    /// under its support is nearer than `near`, and a texel farther than `far` lies behind it
    /// and stays behind. A receiver left out has no texel under its support nearer than its
    /// own surface there, so it is lit, and stays lit after clamping: beyond `far` it and its
    /// whole support clamp onto `span` (`z − d = 0`, lit once offset); before `near` it clamps
    /// onto 0 and its support to `≥ 0`. The tighter interval is what the convolution shadow
    /// map paper asks of the light frustum ("tightly fitted"): it shrinks the offset and the
    /// smooth step's half-width in world units. It is never narrower than
    /// [`MIN_RANGE_RELATIVE`] of the depths, so receivers at a single light depth (a point
    /// light's cube face looking straight down at a floor) are not normalized by their
    /// rounding error. Where no receiver may be shadowed, it spans every receiver and its
    /// support; it falls back to [`Self::of_map`] when the view shades no receiver.
    pub fn fitted(
        map: &DepthBuffer,
        view: &LightView,
        receivers: &ReceiverDepths,
        span: f32,
    ) -> Self {
        let (near, far) = if receivers.shadowable > 0 {
            (receivers.shadowable_near, receivers.shadowable_far)
        } else {
            (receivers.near, receivers.far)
        };
        if receivers.count == 0 || !near.is_finite() || !far.is_finite() || near > far {
            return Self::of_map(map, view, span);
        }
        // Receivers that all lie at one light depth (a plane facing the light head-on) give
        // an interval as thin as the depths' rounding; widen it towards the light so that
        // rounding stays far below the filters' offsets and transition widths.
        let near = near.min(far - Self::min_width(near, far));
        // A sliver of slack on both sides so the nearest occluder and the farthest receiver
        // are not both clamped onto the ends.
        let slack = (far - near) * FITTED_RANGE_SLACK;
        DepthRange {
            near: near - slack,
            far: far + slack,
            span,
        }
    }

    /// `depth` mapped to `[0, span]`, clamped; empty texels (`+inf`) map to `span`.
    #[inline]
    pub fn normalize(&self, depth: f32) -> f32 {
        if depth.is_nan() {
            return self.span;
        }
        ((depth - self.near) / (self.far - self.near)).clamp(0.0, 1.0) * self.span
    }
}

/// Narrowest depth interval a map is normalized over, as a fraction of the depths' magnitude
/// (see [`DepthRange::fitted`]). Rasterized and projected depths of the same point differ by
/// a few units in the last place (about 10⁻⁷ relative); normalized over an interval that
/// thin, that rounding fills the whole `[0, span]` and flat receivers shadow themselves. At
/// 10⁻³ the rounding is 10⁻⁴ of the interval, far below `csm`'s offset and `vsm`'s variance
/// floor, while receivers a thousandth of their light distance apart still separate.
pub const MIN_RANGE_RELATIVE: f32 = 1e-3;

/// Fraction of the fitted depth interval added on each side (see [`DepthRange::fitted`]):
/// keeps the extreme depths off the clamped ends at the cost of 1% of the precision.
pub const FITTED_RANGE_SLACK: f32 = 0.005;
