//! PNG figures with plotters: an embedded DejaVu font (no system fonts needed), atomic writes
//! (drawn in memory, encoded with `png`, written to a temporary file, then renamed), and one
//! small chart helper that covers the report's line, point and threshold plots.

use crate::files::{write_atomic, WriteError};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Backend of every figure.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn fonts() {
    static DONE: OnceLock<()> = OnceLock::new();
    DONE.get_or_init(|| {
        // DejaVu Sans is a valid TrueType font; registration cannot fail for it.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

/// Draws a `w` x `h` PNG at `path` through `draw`: drawn into memory (24-bit RGB), encoded,
/// and written atomically through [`write_atomic`], so an interrupted run leaves no partial
/// figure and no temporary file.
pub fn write_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> DrawResult,
) -> Result<(), WriteError> {
    fonts();
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    let r = (|| -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    })();
    if let Err(e) = r {
        return Err(WriteError {
            path: path.to_path_buf(),
            source: std::io::Error::other(format!("drawing failed: {e}")),
        });
    }
    write_atomic(path, |w| {
        let mut enc = png::Encoder::new(w, size.0, size.1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
        let mut out = enc.write_header().map_err(std::io::Error::other)?;
        out.write_image_data(&rgb).map_err(std::io::Error::other)?;
        out.finish().map_err(std::io::Error::other)
    })
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    Line,
    Dots,
    LineDots,
    /// A dashed line through dots (a second set of lines beside `LineDots` in the same colours).
    DashedDots,
}

/// An axis tick's label: at most three decimals, trailing zeros dropped; roundoff around zero
/// (below 1e-12) shown as 0, other magnitudes below 1e-3 in exponent form.
fn tick(v: f64) -> String {
    if v.abs() < 1e-12 {
        return "0".to_string();
    }
    if v.abs() < 1e-3 {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        "-0" => "0".to_string(),
        _ => s.to_string(),
    }
}

/// One named series of (x, y) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub mark: Mark,
    /// Palette index.
    pub color: usize,
}

/// A horizontal or vertical reference line.
pub struct Rule {
    pub name: String,
    pub value: f64,
    pub vertical: bool,
    pub color: usize,
}

/// A chart: title, axis labels, series and rules; ranges cover all data with 5 % margins.
pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: Vec<Series>,
    pub rules: Vec<Rule>,
    /// Fixed ranges (None: from the data).
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
}

/// The palette (colour-blind friendly, Okabe-Ito), then black.
pub fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 8] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(120, 120, 120),
        RGBColor(0, 0, 0),
    ];
    P[i % P.len()]
}

fn span(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 * hi.abs().max(1.0) {
        let d = 0.5 * hi.abs().max(1.0);
        return (lo - d, hi + d);
    }
    let m = 0.05 * (hi - lo);
    (lo - m, hi + m)
}

impl Chart<'_> {
    /// Draws the chart into `area`.
    pub fn draw(&self, area: &Area<'_>) -> DrawResult {
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0));
        let xr = self.rules.iter().filter(|r| r.vertical).map(|r| r.value);
        let x = self.x_range.unwrap_or_else(|| span(xs.chain(xr)));
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1));
        let yr = self.rules.iter().filter(|r| !r.vertical).map(|r| r.value);
        let y = self.y_range.unwrap_or_else(|| span(ys.chain(yr)));
        let mut chart = ChartBuilder::on(area)
            .caption(self.title, ("sans-serif", 20).into_font())
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 13))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        for s in &self.series {
            let c = color(s.color);
            if matches!(s.mark, Mark::Line | Mark::LineDots) {
                let e = chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))?;
                if !s.name.is_empty() {
                    e.label(s.name.clone()).legend(move |(a, b)| {
                        PathElement::new(vec![(a, b), (a + 18, b)], c.stroke_width(2))
                    });
                }
            }
            if s.mark == Mark::DashedDots {
                let e = chart.draw_series(DashedLineSeries::new(
                    s.points.iter().copied(),
                    8,
                    5,
                    c.stroke_width(2),
                ))?;
                if !s.name.is_empty() {
                    e.label(s.name.clone()).legend(move |(a, b)| {
                        PathElement::new(vec![(a, b), (a + 7, b)], c.stroke_width(2))
                    });
                }
            }
            if matches!(s.mark, Mark::Dots | Mark::LineDots | Mark::DashedDots) {
                let e =
                    chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
                if !s.name.is_empty() && s.mark == Mark::Dots {
                    e.label(s.name.clone())
                        .legend(move |(a, b)| Circle::new((a + 9, b), 3, c.filled()));
                }
            }
        }
        for r in &self.rules {
            let c = color(r.color);
            let pts = if r.vertical {
                vec![(r.value, y.0), (r.value, y.1)]
            } else {
                vec![(x.0, r.value), (x.1, r.value)]
            };
            let e = chart.draw_series(DashedLineSeries::new(pts, 6, 4, c.stroke_width(2)))?;
            if !r.name.is_empty() {
                e.label(r.name.clone()).legend(move |(a, b)| {
                    PathElement::new(vec![(a, b), (a + 18, b)], c.stroke_width(2))
                });
            }
        }
        if self.series.iter().any(|s| !s.name.is_empty())
            || self.rules.iter().any(|r| !r.name.is_empty())
        {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .label_font(("sans-serif", 13))
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }
        Ok(())
    }
}

/// Bar heights per group (outer) and bar (inner), with optional error half-widths of the same
/// shape (empty: no whiskers).
pub struct BarData<'a> {
    pub groups: &'a [Vec<f64>],
    pub errors: &'a [Vec<f64>],
}

/// The whiskers of bar k in every group (bar width `w`): value +- error as a vertical line
/// with short caps, clipped at zero; none where the error `err(g, k)` is missing, NaN or
/// not positive.
fn whisker_paths(
    groups: &[Vec<f64>],
    err: &dyn Fn(usize, usize) -> Option<f64>,
    k: usize,
    w: f64,
) -> Vec<Vec<(f64, f64)>> {
    let mut paths = Vec::new();
    for (g, v) in groups.iter().enumerate() {
        let (Some(&val), Some(e)) = (v.get(k), err(g, k)) else {
            continue;
        };
        if e.is_nan() || e <= 0.0 {
            continue;
        }
        let xm = g as f64 + 0.1 + k as f64 * w + w * 0.45;
        let cap = w * 0.2;
        let lo = (val - e).max(0.0);
        let hi = val + e;
        paths.push(vec![(xm, lo), (xm, hi)]);
        paths.push(vec![(xm - cap, lo), (xm + cap, lo)]);
        paths.push(vec![(xm - cap, hi), (xm + cap, hi)]);
    }
    paths
}

/// A bar chart of labelled groups: `groups[g][k]` is bar k of group g (e.g. cylinders x
/// points), with optional horizontal rules (thresholds).
pub fn bars(
    area: &Area<'_>,
    title: &str,
    y_label: &str,
    group_names: &[String],
    bar_names: &[String],
    data: BarData<'_>,
    rules: &[Rule],
) -> DrawResult {
    let BarData { groups, errors } = data;
    let nb = bar_names.len().max(1);
    let err = |g: usize, k: usize| errors.get(g).and_then(|e| e.get(k)).copied();
    let ymax = groups
        .iter()
        .enumerate()
        .flat_map(|(g, v)| v.iter().enumerate().map(move |(k, x)| (g, k, *x)))
        .map(|(g, k, x)| x + err(g, k).unwrap_or(0.0))
        .chain(rules.iter().map(|r| r.value))
        .fold(0.0f64, f64::max)
        * 1.12;
    let n = groups.len();
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20).into_font())
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..n as f64, 0.0..ymax.max(1e-12))?;
    let names = group_names.to_vec();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n.max(1) * 2 + 1)
        .x_label_formatter(&move |v| {
            let k = v.floor() as usize;
            if (v - k as f64 - 0.5).abs() < 0.01 && k < names.len() {
                names[k].clone()
            } else {
                String::new()
            }
        })
        .y_label_formatter(&|v| tick(*v))
        .y_desc(y_label)
        .label_style(("sans-serif", 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    let w = 0.8 / nb as f64;
    for k in 0..nb {
        let c = color(k);
        let e = chart.draw_series(groups.iter().enumerate().filter_map(|(g, v)| {
            let val = *v.get(k)?;
            let x0 = g as f64 + 0.1 + k as f64 * w;
            Some(Rectangle::new([(x0, 0.0), (x0 + w * 0.9, val)], c.filled()))
        }))?;
        if let Some(name) = bar_names.get(k) {
            e.label(name.clone())
                .legend(move |(a, b)| Rectangle::new([(a, b - 5), (a + 12, b + 5)], c.filled()));
        }
        // whiskers: value +- error, a vertical line with short caps
        let black = BLACK.stroke_width(1);
        chart.draw_series(
            whisker_paths(groups, &err, k, w)
                .into_iter()
                .map(|pts| PathElement::new(pts, black)),
        )?;
    }
    for r in rules {
        let c = color(r.color);
        let e = chart.draw_series(DashedLineSeries::new(
            vec![(0.0, r.value), (n as f64, r.value)],
            6,
            4,
            c.stroke_width(2),
        ))?;
        e.label(r.name.clone())
            .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 18, b)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::tick;

    /// Tick labels: roundoff at zero is 0 (the pin-offset axis read "-0.0"), decimals trimmed.
    #[test]
    fn tick_labels() {
        assert_eq!(tick(-2.2e-17), "0");
        assert_eq!(tick(1600.0), "1600");
        assert_eq!(tick(-0.2), "-0.2");
        assert_eq!(tick(0.125), "0.125");
        assert_eq!(tick(2.5e-5), "2.5e-5");
    }
}
