//! Small SVG chart builders on plotters' SVG backend. Libraries return data; the CLI renders it
//! here. Every builder returns the SVG document as a `String`.
//!
//! No font files are needed: the SVG backend writes `<text>` elements and the viewer picks the
//! font (`sans-serif`). Each document carries a `<desc>` line such as
//! `mte-plot: xy chart, 3 series` so tests and tools can check what was drawn.
//!
//! Non-finite data are rejected with [`CliError::Plot`] naming the series and the point, so a
//! chart never contains `NaN`.
//!
//! ```
//! use mte::plot::{Axis, Series, XyChart};
//! let svg = XyChart::new("Positioning error of X")
//!     .x_axis(Axis::new("X position", "mm"))
//!     .y_axis(Axis::new("deviation", "µm"))
//!     .series(Series::line("run 1", vec![(0.0, 0.0), (100.0, 2.5), (200.0, 4.0)]))
//!     .series(Series::scatter("run 2", vec![(0.0, 0.4), (100.0, 2.0), (200.0, 4.4)]))
//!     .render()?;
//! assert!(svg.starts_with("<svg"));
//! assert!(svg.contains("mte-plot: xy chart, 2 series"));
//! # Ok::<(), mte::CliError>(())
//! ```

use crate::CliError;
use plotters::prelude::*;

/// Default chart size in pixels.
pub const DEFAULT_SIZE: (u32, u32) = (800, 500);

/// An axis: a quantity and its unit, shown as `"quantity [unit]"`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Axis {
    /// Quantity, e.g. `"X position"`.
    pub label: String,
    /// Unit, e.g. `"mm"` (empty for none).
    pub unit: String,
}

impl Axis {
    /// An axis with a label and a unit.
    pub fn new(label: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            unit: unit.into(),
        }
    }

    /// `"label [unit]"`, or just the label without a unit.
    pub fn text(&self) -> String {
        if self.unit.is_empty() {
            self.label.clone()
        } else {
            format!("{} [{}]", self.label, self.unit)
        }
    }
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Connected line.
    Line,
    /// Markers only.
    Scatter,
    /// Line with markers.
    LineMarkers,
}

/// One named data series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: SeriesStyle,
}

impl Series {
    /// A line series.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::Line,
        }
    }

    /// A scatter (markers only) series.
    pub fn scatter(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::Scatter,
        }
    }

    /// A line with markers.
    pub fn line_markers(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::LineMarkers,
        }
    }
}

/// Line/scatter chart with several series, axis labels with units and a legend.
#[derive(Debug, Clone, PartialEq)]
pub struct XyChart {
    title: String,
    x: Axis,
    y: Axis,
    series: Vec<Series>,
    size: (u32, u32),
    zero_line: bool,
}

impl XyChart {
    /// An empty chart with a title.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            x: Axis::default(),
            y: Axis::default(),
            series: Vec::new(),
            size: DEFAULT_SIZE,
            zero_line: false,
        }
    }

    /// Sets the x axis.
    pub fn x_axis(mut self, axis: Axis) -> Self {
        self.x = axis;
        self
    }

    /// Sets the y axis.
    pub fn y_axis(mut self, axis: Axis) -> Self {
        self.y = axis;
        self
    }

    /// Adds a series.
    pub fn series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Size in pixels (width, height).
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.size = (width, height);
        self
    }

    /// Draws a horizontal line at y = 0 (for residuals).
    pub fn zero_line(mut self, on: bool) -> Self {
        self.zero_line = on;
        self
    }

    /// Renders the SVG.
    ///
    /// # Errors
    /// [`CliError::Plot`] for no series, an empty series, a non-finite point (named), or a
    /// backend failure.
    pub fn render(&self) -> Result<String, CliError> {
        let err = |detail: String| CliError::Plot {
            title: self.title.clone(),
            detail,
        };
        if self.series.is_empty() {
            return Err(err("no series to draw".into()));
        }
        for s in &self.series {
            if s.points.is_empty() {
                return Err(err(format!("series {:?} has no points", s.label)));
            }
            check_points(&s.label, &s.points).map_err(err)?;
        }
        let all = self.series.iter().flat_map(|s| s.points.iter());
        let (xr, yr) = ranges(all, self.zero_line);
        let mut buf = String::new();
        {
            let root = SVGBackend::with_string(&mut buf, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
                .map_err(|e| err(e.to_string()))?;
            chart
                .configure_mesh()
                .x_desc(self.x.text())
                .y_desc(self.y.text())
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|e| err(e.to_string()))?;
            if self.zero_line {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(xr.0, 0.0), (xr.1, 0.0)],
                        BLACK.mix(0.5),
                    )))
                    .map_err(|e| err(e.to_string()))?;
            }
            for (i, s) in self.series.iter().enumerate() {
                let color = palette(i);
                let pts = s.points.clone();
                let anno = match s.style {
                    SeriesStyle::Line => chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                        .map_err(|e| err(e.to_string()))?,
                    SeriesStyle::Scatter => chart
                        .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                        .map_err(|e| err(e.to_string()))?,
                    SeriesStyle::LineMarkers => chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)).point_size(3))
                        .map_err(|e| err(e.to_string()))?,
                };
                anno.label(s.label.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| err(e.to_string()))?;
            root.present().map_err(|e| err(e.to_string()))?;
        }
        Ok(annotate(
            buf,
            &format!("xy chart, {} series", self.series.len()),
        ))
    }
}

/// A value with an interval, for [`error_bar_chart`]: e.g. an identified parameter ± its
/// expanded uncertainty, or a sensitivity index with its bootstrap interval.
#[derive(Debug, Clone, PartialEq)]
pub struct Interval {
    /// Category label (x axis).
    pub label: String,
    /// Estimate (bar height).
    pub value: f64,
    /// Lower end of the interval.
    pub low: f64,
    /// Upper end of the interval.
    pub high: f64,
}

impl Interval {
    /// `value` with the symmetric interval `value ± half_width`.
    pub fn symmetric(label: impl Into<String>, value: f64, half_width: f64) -> Self {
        Self {
            label: label.into(),
            value,
            low: value - half_width,
            high: value + half_width,
        }
    }
}

/// Bar chart of values with error bars (whiskers from `low` to `high`), one bar per category.
///
/// # Errors
/// [`CliError::Plot`] for no bars, a non-finite value (named) or `low > high`.
///
/// ```
/// use mte::plot::{error_bar_chart, Axis, Interval};
/// let svg = error_bar_chart(
///     "First-order Sobol indices",
///     &Axis::new("S_i", ""),
///     &[Interval::symmetric("EXX", 0.6, 0.05), Interval::symmetric("EYX", 0.3, 0.04)],
/// )?;
/// assert!(svg.contains("2 bars"));
/// # Ok::<(), mte::CliError>(())
/// ```
pub fn error_bar_chart(title: &str, y: &Axis, bars: &[Interval]) -> Result<String, CliError> {
    let err = |detail: String| CliError::Plot {
        title: title.to_string(),
        detail,
    };
    if bars.is_empty() {
        return Err(err("no bars to draw".into()));
    }
    for b in bars {
        for (what, v) in [("value", b.value), ("low", b.low), ("high", b.high)] {
            if !v.is_finite() {
                return Err(err(format!("bar {:?}: {what} is {v}", b.label)));
            }
        }
        if b.low > b.high {
            return Err(err(format!(
                "bar {:?}: interval low {} > high {}",
                b.label, b.low, b.high
            )));
        }
    }
    let n = bars.len();
    let ys = bars
        .iter()
        .flat_map(|b| [(0.0, b.value), (0.0, b.low), (0.0, b.high), (0.0, 0.0)]);
    let (_, yr) = ranges(ys.collect::<Vec<_>>().iter(), true);
    let labels: Vec<String> = bars.iter().map(|b| b.label.clone()).collect();
    let fmt = |v: &f64| -> String {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
            labels[i as usize].clone()
        } else {
            String::new()
        }
    };
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, DEFAULT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), yr.0..yr.1)
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n + 1)
            .x_label_formatter(&fmt)
            .y_desc(y.text())
            .draw()
            .map_err(|e| err(e.to_string()))?;
        let color = palette(0);
        chart
            .draw_series(bars.iter().enumerate().map(|(i, b)| {
                let x = i as f64;
                Rectangle::new(
                    [(x - 0.3, 0.0), (x + 0.3, b.value)],
                    color.mix(0.6).filled(),
                )
            }))
            .map_err(|e| err(e.to_string()))?;
        chart
            .draw_series(bars.iter().enumerate().flat_map(|(i, b)| {
                let x = i as f64;
                [
                    PathElement::new(vec![(x, b.low), (x, b.high)], BLACK.stroke_width(2)),
                    PathElement::new(
                        vec![(x - 0.1, b.low), (x + 0.1, b.low)],
                        BLACK.stroke_width(2),
                    ),
                    PathElement::new(
                        vec![(x - 0.1, b.high), (x + 0.1, b.high)],
                        BLACK.stroke_width(2),
                    ),
                ]
            }))
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(annotate(buf, &format!("error-bar chart, {n} bars")))
}

/// Residuals against one variable (e.g. residual in µm against axis position), one scatter
/// group per series, with a zero line.
///
/// # Errors
/// As [`XyChart::render`].
///
/// ```
/// use mte::plot::{residual_plot, Axis, Series};
/// let svg = residual_plot(
///     "Residuals after the base fit",
///     &Axis::new("X", "mm"),
///     &Axis::new("residual", "µm"),
///     &[Series::scatter("forward", vec![(0.0, 0.2), (50.0, -0.1)]),
///       Series::scatter("backward", vec![(0.0, -0.3), (50.0, 0.4)])],
/// )?;
/// assert!(svg.contains("2 series"));
/// # Ok::<(), mte::CliError>(())
/// ```
pub fn residual_plot(
    title: &str,
    x: &Axis,
    residual: &Axis,
    groups: &[Series],
) -> Result<String, CliError> {
    let mut chart = XyChart::new(title)
        .x_axis(x.clone())
        .y_axis(residual.clone())
        .zero_line(true);
    for g in groups {
        chart = chart.series(Series {
            style: SeriesStyle::Scatter,
            ..g.clone()
        });
    }
    chart.render()
}

/// A regular 2-D grid of a scalar (colour) with optional in-plane vectors (arrows), e.g. the
/// volumetric error over an XY plane: colour = |error| in µm, arrows = (δx, δy).
#[derive(Debug, Clone, PartialEq)]
pub struct FieldMap {
    /// Grid coordinates along x (strictly increasing).
    pub xs: Vec<f64>,
    /// Grid coordinates along y (strictly increasing).
    pub ys: Vec<f64>,
    /// `values[j][i]` at `(xs[i], ys[j])`.
    pub values: Vec<Vec<f64>>,
    /// Optional arrows `arrows[j][i] = (dx, dy)` at the grid points, in the unit of `values`.
    pub arrows: Option<Vec<Vec<(f64, f64)>>>,
    /// Unit of `values` and arrows, e.g. `"µm"`.
    pub unit: String,
}

/// Heat map of a [`FieldMap`] with arrows; the longest arrow is drawn 0.9 grid cells long, and
/// the caption states the colour range and the arrow scale.
///
/// # Errors
/// [`CliError::Plot`] for a grid of fewer than 2 × 2 points, non-increasing coordinates,
/// mismatched sizes or non-finite values (named by grid index).
///
/// ```
/// use mte::plot::{heat_arrow_map, Axis, FieldMap};
/// let xs = vec![0.0, 100.0, 200.0];
/// let ys = vec![0.0, 100.0];
/// let values = vec![vec![1.0, 2.0, 3.0], vec![2.0, 3.0, 4.0]];
/// let arrows = Some(vec![vec![(1.0, 0.0); 3], vec![(0.0, 1.0); 3]]);
/// let map = FieldMap { xs, ys, values, arrows, unit: "µm".into() };
/// let svg = heat_arrow_map("Volumetric error, Z = 0", &Axis::new("X", "mm"), &Axis::new("Y", "mm"), &map)?;
/// assert!(svg.contains("6 cells, 6 arrows"));
/// # Ok::<(), mte::CliError>(())
/// ```
pub fn heat_arrow_map(title: &str, x: &Axis, y: &Axis, map: &FieldMap) -> Result<String, CliError> {
    let err = |detail: String| CliError::Plot {
        title: title.to_string(),
        detail,
    };
    let (nx, ny) = (map.xs.len(), map.ys.len());
    if nx < 2 || ny < 2 {
        return Err(err(format!("grid is {nx} × {ny}, need at least 2 × 2")));
    }
    for (name, c) in [("xs", &map.xs), ("ys", &map.ys)] {
        if let Some(i) = (0..c.len()).find(|&i| !c[i].is_finite()) {
            return Err(err(format!("{name}[{i}] is {}", c[i])));
        }
        if let Some(i) = (1..c.len()).find(|&i| c[i] <= c[i - 1]) {
            return Err(err(format!("{name} not strictly increasing at index {i}")));
        }
    }
    if map.values.len() != ny || map.values.iter().any(|r| r.len() != nx) {
        return Err(err(format!("values must be {ny} rows of {nx}")));
    }
    for (j, r) in map.values.iter().enumerate() {
        if let Some(i) = r.iter().position(|v| !v.is_finite()) {
            return Err(err(format!("values[{j}][{i}] is {}", r[i])));
        }
    }
    if let Some(a) = &map.arrows {
        if a.len() != ny || a.iter().any(|r| r.len() != nx) {
            return Err(err(format!("arrows must be {ny} rows of {nx}")));
        }
        for (j, r) in a.iter().enumerate() {
            if let Some(i) = r.iter().position(|v| !v.0.is_finite() || !v.1.is_finite()) {
                return Err(err(format!("arrows[{j}][{i}] is not finite")));
            }
        }
    }
    let vmin = map
        .values
        .iter()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let vmax = map
        .values
        .iter()
        .flatten()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    // cell edges halfway between grid points
    let edges = |c: &[f64]| -> Vec<f64> {
        let mut e = vec![c[0] - (c[1] - c[0]) / 2.0];
        for w in c.windows(2) {
            e.push((w[0] + w[1]) / 2.0);
        }
        e.push(c[c.len() - 1] + (c[c.len() - 1] - c[c.len() - 2]) / 2.0);
        e
    };
    let (ex, ey) = (edges(&map.xs), edges(&map.ys));
    let cell = (ex[nx] - ex[0]) / nx as f64;
    let cell = cell.min((ey[ny] - ey[0]) / ny as f64);
    let amax = map
        .arrows
        .iter()
        .flatten()
        .flatten()
        .map(|(dx, dy)| dx.hypot(*dy))
        .fold(0.0, f64::max);
    let scale = if amax > 0.0 { 0.9 * cell / amax } else { 0.0 };
    let caption = format!(
        "{title} (colour {} … {} {}{})",
        crate::report::fmt_sig(vmin, 3),
        crate::report::fmt_sig(vmax, 3),
        map.unit,
        if amax > 0.0 {
            format!(
                "; longest arrow {} {}",
                crate::report::fmt_sig(amax, 3),
                map.unit
            )
        } else {
            String::new()
        }
    );
    let n_arrows = map.arrows.as_ref().map_or(0, |_| nx * ny);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, DEFAULT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&caption, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(ex[0]..ex[nx], ey[0]..ey[ny])
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(x.text())
            .y_desc(y.text())
            .draw()
            .map_err(|e| err(e.to_string()))?;
        let span = if vmax > vmin { vmax - vmin } else { 1.0 };
        chart
            .draw_series((0..ny).flat_map(|j| {
                let ex = &ex;
                let ey = &ey;
                let values = &map.values;
                (0..nx).map(move |i| {
                    let t = (values[j][i] - vmin) / span;
                    Rectangle::new(
                        [(ex[i], ey[j]), (ex[i + 1], ey[j + 1])],
                        heat_color(t).filled(),
                    )
                })
            }))
            .map_err(|e| err(e.to_string()))?;
        if let Some(arrows) = &map.arrows {
            let mut paths = Vec::new();
            for (row, &y0) in arrows.iter().zip(&map.ys) {
                for (&(ax, ay), &x0) in row.iter().zip(&map.xs) {
                    let (dx, dy) = (ax * scale, ay * scale);
                    let (x1, y1) = (x0 + dx, y0 + dy);
                    paths.push(PathElement::new(
                        vec![(x0, y0), (x1, y1)],
                        BLACK.stroke_width(1),
                    ));
                    let len = dx.hypot(dy);
                    if len > 0.0 {
                        // two head strokes at ±25° of the reversed direction, 30 % of the length
                        let (ux, uy) = (-dx / len, -dy / len);
                        let h = 0.3 * len;
                        for ang in [0.436_f64, -0.436] {
                            let (c, s) = (ang.cos(), ang.sin());
                            let hx = x1 + h * (c * ux - s * uy);
                            let hy = y1 + h * (s * ux + c * uy);
                            paths.push(PathElement::new(
                                vec![(x1, y1), (hx, hy)],
                                BLACK.stroke_width(1),
                            ));
                        }
                    }
                }
            }
            chart.draw_series(paths).map_err(|e| err(e.to_string()))?;
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(annotate(
        buf,
        &format!("heat map, {} cells, {n_arrows} arrows", nx * ny),
    ))
}

fn check_points(label: &str, pts: &[(f64, f64)]) -> Result<(), String> {
    match pts
        .iter()
        .position(|(x, y)| !x.is_finite() || !y.is_finite())
    {
        Some(i) => Err(format!(
            "series {label:?}: point {i} = ({}, {}) is not finite",
            pts[i].0, pts[i].1
        )),
        None => Ok(()),
    }
}

/// Data range padded by 5 %, widened when degenerate; optionally includes y = 0.
fn ranges<'a>(
    pts: impl Iterator<Item = &'a (f64, f64)>,
    include_zero_y: bool,
) -> ((f64, f64), (f64, f64)) {
    let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
    let mut yr = if include_zero_y {
        (0.0, 0.0)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY)
    };
    for &(x, y) in pts {
        xr = (xr.0.min(x), xr.1.max(x));
        yr = (yr.0.min(y), yr.1.max(y));
    }
    (pad(xr), pad(yr))
}

/// An axis range a chart can draw: finite ends within ±1e100 and `lo ≤ hi`; non-finite or
/// reversed ends give (0, 1). Plot-axis tick computations loop forever or panic on infinite
/// spans, so every range goes through here.
///
/// ```
/// use mte::plot::finite_range;
/// assert_eq!(finite_range(-2.0, 3.0), (-2.0, 3.0));
/// assert_eq!(finite_range(f64::NEG_INFINITY, f64::INFINITY), (0.0, 1.0));
/// assert_eq!(finite_range(f64::NAN, 1.0), (0.0, 1.0));
/// assert_eq!(finite_range(-1e300, 1e300), (-1e100, 1e100));
/// ```
pub fn finite_range(lo: f64, hi: f64) -> (f64, f64) {
    const BIG: f64 = 1e100;
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return (0.0, 1.0);
    }
    (lo.clamp(-BIG, BIG), hi.clamp(-BIG, BIG))
}

fn pad((lo, hi): (f64, f64)) -> (f64, f64) {
    if !lo.is_finite() || !hi.is_finite() || lo > hi {
        return (0.0, 1.0);
    }
    let (lo, hi) = finite_range(lo, hi);
    let span = hi - lo;
    if span <= 0.0 {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        (lo - d, hi + d)
    } else {
        (lo - 0.05 * span, hi + 0.05 * span)
    }
}

/// Colour-blind-safe palette (Okabe–Ito), cycled.
fn palette(i: usize) -> RGBColor {
    const P: [(u8, u8, u8); 7] = [
        (0, 114, 178),
        (213, 94, 0),
        (0, 158, 115),
        (204, 121, 167),
        (230, 159, 0),
        (86, 180, 233),
        (0, 0, 0),
    ];
    let (r, g, b) = P[i % P.len()];
    RGBColor(r, g, b)
}

/// Blue (t = 0) → white (0.5) → red (t = 1).
fn heat_color(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64, s: f64| (a + (b - a) * s).round() as u8;
    if t < 0.5 {
        let s = t / 0.5;
        RGBColor(
            lerp(33.0, 247.0, s),
            lerp(102.0, 247.0, s),
            lerp(172.0, 247.0, s),
        )
    } else {
        let s = (t - 0.5) / 0.5;
        RGBColor(
            lerp(247.0, 178.0, s),
            lerp(247.0, 24.0, s),
            lerp(247.0, 43.0, s),
        )
    }
}

/// Inserts `<desc>mte-plot: …</desc>` right after the opening `<svg …>` tag.
fn annotate(svg: String, what: &str) -> String {
    match svg.find('>') {
        Some(i) if svg.starts_with("<svg") => {
            let mut out = String::with_capacity(svg.len() + what.len() + 32);
            out.push_str(&svg[..=i]);
            out.push_str(&format!("\n<desc>mte-plot: {}</desc>", xml_escape(what)));
            out.push_str(&svg[i + 1..]);
            out
        }
        _ => svg,
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parse-level well-formedness: one root `<svg>` element, balanced tags, no NaN/inf.
    fn assert_well_formed(svg: &str) {
        assert!(svg.starts_with("<svg"), "starts with <svg");
        assert!(svg.trim_end().ends_with("</svg>"), "ends with </svg>");
        assert!(
            !svg.contains("NaN") && !svg.contains("inf"),
            "no non-finite numbers"
        );
        // balanced tags: a stack over <name ...>, </name>, <name .../>
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = rest[start..].find('>').expect("unterminated tag") + start;
            let tag = &rest[start + 1..end];
            rest = &rest[end + 1..];
            if tag.starts_with('?') || tag.starts_with('!') {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().expect("closing tag without opening");
                assert_eq!(open, name.trim(), "mismatched tag");
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().unwrap_or("").to_string();
                stack.push(name);
            }
        }
        assert!(stack.is_empty(), "unclosed tags: {stack:?}");
    }

    #[test]
    fn xy_chart_has_every_series_and_its_legend() {
        let svg = XyChart::new("Straightness EYX")
            .x_axis(Axis::new("X position", "mm"))
            .y_axis(Axis::new("EYX", "µm"))
            .series(Series::line(
                "measured",
                vec![(0.0, 0.0), (1.0, 1.0), (2.0, 0.5)],
            ))
            .series(Series::scatter("model", vec![(0.0, 0.1), (1.0, 0.9)]))
            .series(Series::line_markers(
                "residual",
                vec![(0.0, -0.1), (2.0, 0.2)],
            ))
            .render()
            .unwrap();
        assert_well_formed(&svg);
        assert!(svg.contains("mte-plot: xy chart, 3 series"));
        for text in [
            "measured",
            "model",
            "residual",
            "X position [mm]",
            "EYX [µm]",
            "Straightness EYX",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        // the scatter series is three-point circles: 2 circles of radius 3 at least
        assert!(svg.matches("<circle").count() >= 2);
    }

    #[test]
    fn non_finite_and_empty_inputs_are_errors() {
        let e = XyChart::new("t")
            .series(Series::line("bad", vec![(0.0, f64::NAN)]))
            .render()
            .unwrap_err();
        assert!(e.to_string().contains("\"bad\": point 0"), "{e}");
        assert!(XyChart::new("t").render().is_err());
        assert!(error_bar_chart("t", &Axis::default(), &[]).is_err());
        let inv = Interval {
            label: "p".into(),
            value: 1.0,
            low: 2.0,
            high: 0.0,
        };
        assert!(error_bar_chart("t", &Axis::default(), &[inv]).is_err());
        let map = FieldMap {
            xs: vec![0.0, 1.0],
            ys: vec![0.0, 1.0],
            values: vec![vec![0.0, 1.0], vec![f64::INFINITY, 0.0]],
            arrows: None,
            unit: "µm".into(),
        };
        let e = heat_arrow_map("t", &Axis::default(), &Axis::default(), &map).unwrap_err();
        assert!(e.to_string().contains("values[1][0]"), "{e}");
    }

    #[test]
    fn error_bar_chart_draws_one_bar_and_whisker_per_interval() {
        let bars: Vec<Interval> = (0..4)
            .map(|i| Interval::symmetric(format!("P{i}"), i as f64 - 1.5, 0.3))
            .collect();
        let svg =
            error_bar_chart("Identified parameters", &Axis::new("value", "µm"), &bars).unwrap();
        assert_well_formed(&svg);
        assert!(svg.contains("error-bar chart, 4 bars"));
        for i in 0..4 {
            // plotters writes text content on its own line
            assert!(svg.contains(&format!(">\nP{i}\n</text>")), "label P{i}");
        }
        // bars are filled rects (plus the background); whiskers are 3 polylines per bar
        assert!(svg.matches("<rect").count() > 4);
        assert!(svg.matches("<polyline").count() >= 12);
    }

    #[test]
    fn residual_plot_and_heat_map_are_well_formed() {
        let svg = residual_plot(
            "Residuals",
            &Axis::new("X", "mm"),
            &Axis::new("residual", "µm"),
            &[Series::line("a", vec![(0.0, 1.0), (1.0, -1.0)])],
        )
        .unwrap();
        assert_well_formed(&svg);
        assert!(svg.contains("1 series"));
        let xs: Vec<f64> = (0..5).map(|i| i as f64 * 100.0).collect();
        let ys: Vec<f64> = (0..4).map(|i| i as f64 * 50.0).collect();
        let values: Vec<Vec<f64>> = ys
            .iter()
            .map(|y| xs.iter().map(|x| (x * 0.01 + y * 0.02).sin()).collect())
            .collect();
        let arrows = Some(
            ys.iter()
                .map(|y| xs.iter().map(|x| (x * 1e-3, -y * 1e-3)).collect())
                .collect(),
        );
        let map = FieldMap {
            xs,
            ys,
            values,
            arrows,
            unit: "µm".into(),
        };
        let svg = heat_arrow_map(
            "Volumetric error",
            &Axis::new("X", "mm"),
            &Axis::new("Y", "mm"),
            &map,
        )
        .unwrap();
        assert_well_formed(&svg);
        assert!(svg.contains("heat map, 20 cells, 20 arrows"));
        // one rect per cell plus the background
        assert!(svg.matches("<rect").count() >= 21);
    }
}
