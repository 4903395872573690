//! Charts as SVG, drawn with `plotters`, for the report's plots and the bench suites':
//! labelled scatter plots (error against time, one point per technique) and line plots
//! (error or time against a swept parameter, time per frame). Every axis carries a
//! description with its unit.
//!
//! Axes are linear or logarithmic (for quantities spanning decades, such as frame times
//! from a shadow map to the ray tracer), or categorical when a swept parameter is not a
//! number. Text is laid out with plotters' built-in size estimate, so the SVG needs no font
//! files and renders in any browser.

use anyhow::{anyhow, Result};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Width of every plot in SVG pixels.
pub const WIDTH: u32 = 640;
/// Height of every plot in SVG pixels.
pub const HEIGHT: u32 = 420;

/// Points right of this fraction of the x axis carry their label on their left.
const LABEL_FLIP: f64 = 0.7;

/// Series colours (Tableau 10): distinguishable, also in print.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of series or point `i`.
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// How an axis maps values.
#[derive(Clone, Debug, PartialEq)]
pub enum Scale {
    /// Linear from zero (or the smallest value, if negative) to the largest.
    Linear,
    /// Logarithmic over the values' span; every value must be positive.
    Log,
    /// Named categories at 0, 1, 2, …: the values are indices into the names.
    Categories(Vec<String>),
}

/// An axis: its description (quantity and unit) and its scale.
#[derive(Clone, Debug)]
pub struct Axis {
    /// What the axis measures, with its unit, e.g. "frame time (ms)".
    pub desc: String,
    /// The mapping.
    pub scale: Scale,
}

impl Axis {
    /// A linear axis.
    pub fn linear(desc: impl Into<String>) -> Self {
        Axis {
            desc: desc.into(),
            scale: Scale::Linear,
        }
    }

    /// A logarithmic axis.
    pub fn log(desc: impl Into<String>) -> Self {
        Axis {
            desc: desc.into(),
            scale: Scale::Log,
        }
    }

    /// A logarithmic axis when every value is positive and they span at least `ratio`,
    /// else linear.
    pub fn auto(desc: impl Into<String>, values: &[f64], ratio: f64) -> Self {
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo > 0.0 && hi / lo >= ratio {
            Axis::log(desc)
        } else {
            Axis::linear(desc)
        }
    }
}

/// One labelled point of a scatter plot.
#[derive(Clone, Debug)]
pub struct Point {
    /// The label drawn beside the point.
    pub label: String,
    /// Position along the x axis.
    pub x: f64,
    /// Position along the y axis.
    pub y: f64,
}

/// One named line of a line plot.
#[derive(Clone, Debug)]
pub struct Series {
    /// The legend entry.
    pub name: String,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// What a plot draws.
enum Body<'a> {
    Scatter(&'a [Point]),
    Lines(&'a [Series]),
}

impl Body<'_> {
    fn values(&self) -> (Vec<f64>, Vec<f64>) {
        match self {
            Body::Scatter(p) => (
                p.iter().map(|p| p.x).collect(),
                p.iter().map(|p| p.y).collect(),
            ),
            Body::Lines(s) => (
                s.iter()
                    .flat_map(|s| s.points.iter().map(|p| p.0))
                    .collect(),
                s.iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1))
                    .collect(),
            ),
        }
    }
}

/// A scatter plot of labelled points.
pub fn scatter(title: &str, x: &Axis, y: &Axis, points: &[Point]) -> Result<String> {
    plot(title, x, y, Body::Scatter(points))
}

/// A line plot of named series, with a legend.
pub fn lines(title: &str, x: &Axis, y: &Axis, series: &[Series]) -> Result<String> {
    plot(title, x, y, Body::Lines(series))
}

/// The span an axis shows for `values`.
fn span(scale: &Scale, values: &[f64], what: &str) -> Result<(f64, f64)> {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.len() != values.len() {
        return Err(anyhow!(
            "plot axis {what:?} has a value that is not a finite number"
        ));
    }
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok(match scale {
        Scale::Categories(names) => (-0.5, names.len().max(1) as f64 - 0.5),
        Scale::Log => {
            if finite.is_empty() {
                (1.0, 10.0)
            } else if lo <= 0.0 {
                return Err(anyhow!(
                    "plot axis {what:?} is logarithmic but has the value {lo}"
                ));
            } else {
                // A quarter decade of margin so end points are not drawn on the frame.
                let m = 10f64.powf(0.25);
                (lo / m, hi * m)
            }
        }
        Scale::Linear => {
            if finite.is_empty() {
                (0.0, 1.0)
            } else {
                let lo = lo.min(0.0);
                let hi = if hi > lo { hi } else { lo + 1.0 };
                (lo, hi + (hi - lo) * 0.08)
            }
        }
    })
}

/// A number printed short: 3 significant digits, no trailing noise.
pub fn short(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.1e}");
    }
    let digits = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn plot(title: &str, x: &Axis, y: &Axis, body: Body) -> Result<String> {
    let (xs, ys) = body.values();
    let xr = span(&x.scale, &xs, &x.desc)?;
    let yr = span(&y.scale, &ys, &y.desc)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        // Labels of points in the right part of the plot go to their left, inside the frame.
        let right = |v: f64| {
            let t = match x.scale {
                Scale::Log => (v.ln() - xr.0.ln()) / (xr.1.ln() - xr.0.ln()),
                _ => (v - xr.0) / (xr.1 - xr.0),
            };
            t > LABEL_FLIP
        };
        let spec = Spec {
            title,
            x,
            y,
            body: &body,
            right: &right,
        };
        // Each scale has its own coordinate type, so dispatch once to a monomorphized body.
        match (&x.scale, &y.scale) {
            (Scale::Log, Scale::Log) => draw(
                &root,
                &spec,
                (xr.0..xr.1).log_scale(),
                (yr.0..yr.1).log_scale(),
            )?,
            (Scale::Log, _) => draw(&root, &spec, (xr.0..xr.1).log_scale(), yr.0..yr.1)?,
            (_, Scale::Log) => draw(&root, &spec, xr.0..xr.1, (yr.0..yr.1).log_scale())?,
            _ => draw(&root, &spec, xr.0..xr.1, yr.0..yr.1)?,
        }
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

fn draw_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("cannot draw plot: {e:?}")
}

fn tick_label(scale: &Scale, v: f64) -> String {
    match scale {
        Scale::Categories(names) => {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
                names[i as usize].clone()
            } else {
                String::new()
            }
        }
        _ => short(v),
    }
}

/// Everything a plot shows but its coordinate ranges.
struct Spec<'a> {
    title: &'a str,
    x: &'a Axis,
    y: &'a Axis,
    body: &'a Body<'a>,
    /// True for x values whose point label goes to the point's left.
    right: &'a dyn Fn(f64) -> bool,
}

fn draw<X, Y>(
    root: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    spec: &Spec,
    xr: X,
    yr: Y,
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let Spec {
        title,
        x,
        y,
        body,
        right,
    } = *spec;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(14)
        .margin_left(22)
        .x_label_area_size(46)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)
        .map_err(draw_err)?;
    let xfmt = |v: &f64| tick_label(&x.scale, *v);
    let yfmt = |v: &f64| tick_label(&y.scale, *v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x.desc.as_str())
        .y_desc(y.desc.as_str())
        .x_label_formatter(&xfmt)
        .y_label_formatter(&yfmt)
        .axis_desc_style(("sans-serif", 14))
        .label_style(("sans-serif", 12))
        .light_line_style(RGBColor(235, 235, 235));
    if let Scale::Categories(names) = &x.scale {
        mesh.x_labels(names.len().max(1)).disable_x_mesh();
    }
    mesh.draw().map_err(draw_err)?;
    match body {
        Body::Scatter(points) => {
            for (i, p) in points.iter().enumerate() {
                let c = color(i);
                let (dx, h) = if right(p.x) {
                    (-7, HPos::Right)
                } else {
                    (7, HPos::Left)
                };
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((p.x, p.y))
                            + Circle::new((0, 0), 5, c.filled())
                            + Text::new(
                                p.label.clone(),
                                (dx, -4),
                                ("sans-serif", 12)
                                    .into_font()
                                    .color(&c)
                                    .pos(Pos::new(h, VPos::Bottom)),
                            ),
                    ))
                    .map_err(draw_err)?;
            }
        }
        Body::Lines(series) => {
            for (i, s) in series.iter().enumerate() {
                let c = color(i);
                // The first line is drawn wide and pale so a later one lying on it stays visible.
                let style = if i == 0 && series.len() > 1 {
                    c.mix(0.45).stroke_width(6)
                } else {
                    c.stroke_width(2)
                };
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), style))
                    .map_err(draw_err)?
                    .label(s.name.clone())
                    .legend(move |(lx, ly)| PathElement::new(vec![(lx, ly), (lx + 18, ly)], style));
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 4, c.filled())))
                    .map_err(draw_err)?;
            }
            // A single line is named by the title; a legend would only hide data.
            if series.len() > 1 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(RGBColor(190, 190, 190))
                    .label_font(("sans-serif", 12))
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(draw_err)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trimmed contents of every `<text>` element.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let body = &t[t.find('>')? + 1..];
                Some(body[..body.find("</text>")?].trim().to_string())
            })
            .collect()
    }

    #[test]
    fn scatter_has_labelled_axes_and_points() {
        let pts = vec![
            Point {
                label: "sm".into(),
                x: 2.0,
                y: 0.05,
            },
            Point {
                label: "raytrace".into(),
                x: 300.0,
                y: 0.0,
            },
        ];
        let svg = scatter(
            "error against time",
            &Axis::log("frame time (ms)"),
            &Axis::linear("mean abs error"),
            &pts,
        )
        .unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(80)]);
        let t = texts(&svg);
        for needle in [
            "frame time (ms)",
            "mean abs error",
            "sm",
            "raytrace",
            "error against time",
        ] {
            assert!(t.iter().any(|x| x == needle), "missing {needle} in {t:?}");
        }
        assert_eq!(svg.matches("<circle").count(), 2);
    }

    #[test]
    fn log_axis_rejects_non_positive_values() {
        let pts = vec![Point {
            label: "x".into(),
            x: 0.0,
            y: 1.0,
        }];
        let e = scatter("t", &Axis::log("time (ms)"), &Axis::linear("e"), &pts).unwrap_err();
        assert!(e.to_string().contains("time (ms)"), "{e}");
    }

    #[test]
    fn categorical_axis_names_each_value() {
        let s = vec![Series {
            name: "csm".into(),
            points: vec![(0.0, 1.0), (1.0, 2.0), (2.0, 1.5)],
        }];
        let names = vec!["none".to_string(), "3x3".to_string(), "7x7".to_string()];
        let svg = lines(
            "t",
            &Axis {
                desc: "blur".into(),
                scale: Scale::Categories(names.clone()),
            },
            &Axis::linear("time (ms)"),
            &s,
        )
        .unwrap();
        for n in &names {
            assert!(texts(&svg).contains(n), "missing category {n}");
        }
    }

    #[test]
    fn auto_axis_goes_logarithmic_over_wide_spans() {
        assert_eq!(Axis::auto("r", &[512.0, 4096.0], 4.0).scale, Scale::Log);
        assert_eq!(Axis::auto("r", &[4.0, 8.0], 4.0).scale, Scale::Linear);
        assert_eq!(Axis::auto("r", &[0.0, 8.0], 4.0).scale, Scale::Linear);
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.0), "0");
        assert_eq!(short(1024.0), "1024");
        assert_eq!(short(0.0523), "0.0523");
        assert_eq!(short(12.345), "12.3");
        assert_eq!(short(2.5e-5), "2.5e-5");
    }
}
