//! The chart kit: bar and box panels drawn once to SVG and once to PNG (plotters), for the
//! results reports (`report`) and the moving-obstacle scenes (`moving`).

use std::path::Path;

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::draw::ok;
use crate::results::stats::quantile;

/// Something drawable on any plotters backend.
pub(crate) trait Chart {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>;
}

/// Writes `stem.svg` and `stem.png`.
pub(crate) fn render(chart: &impl Chart, stem: &Path) -> Result<()> {
    crate::draw::fonts();
    let (w, h) = chart.size();
    let svg = stem.with_extension("svg");
    {
        let root = SVGBackend::new(&svg, (w, h)).into_drawing_area();
        ok(root.fill(&WHITE))?;
        chart.draw(&root)?;
        ok(root.present())?;
    }
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        ok(root.fill(&WHITE))?;
        chart.draw(&root)?;
        ok(root.present())?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).context("image buffer")?;
    let png = stem.with_extension("png");
    img.save(&png)
        .with_context(|| format!("{}", png.display()))?;
    Ok(())
}

/// A number for an axis or a table: three significant digits, no exponent.
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        let digits = (2.0 - a.log10().floor()) as usize;
        format!("{v:.digits$}")
    }
}

/// A log axis's label for `y` = log10(value): the value at whole decades (1, 10, 100, 0.1, in
/// one format), nothing between them.
pub(crate) fn decade(y: f64) -> String {
    let k = y.round();
    if (y - k).abs() > 1e-6 {
        return String::new();
    }
    let v = 10f64.powi(k as i32);
    if k >= 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.*}", (-k) as usize)
    }
}

/// A linear axis's label, every label of an axis over `lo..hi` with the same decimals (as
/// many as a tenth of the range needs).
pub(crate) fn tick(v: f64, lo: f64, hi: f64) -> String {
    let step = ((hi - lo) / 10.0).max(1e-12);
    let decimals = (-step.log10()).ceil().max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// Tick count for a log axis over `lo..hi` (log10 units) that lands ticks on whole decades.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> usize {
    ((hi - lo).ceil() as usize + 1).max(2)
}

/// Groups of bars, one panel per (row, column).
pub(crate) struct Bars {
    pub(crate) title: String,
    pub(crate) cols: usize,
    pub(crate) panels: Vec<BarPanel>,
}

pub(crate) struct BarPanel {
    pub(crate) title: String,
    pub(crate) y_label: String,
    pub(crate) log: bool,
    pub(crate) groups: Vec<String>,
    /// Colour and name of each series (the legend box).
    pub(crate) series: Vec<(RGBColor, String)>,
    /// A horizontal reference line and its legend entry (e.g. the exact optimum).
    pub(crate) reference: Option<(f64, String)>,
    /// Linear bars from zero (counts, seconds) instead of from just below the smallest value
    /// (lengths, where a change of 1 % must show).
    pub(crate) from_zero: bool,
    /// `values[group][series]`.
    pub(crate) values: Vec<Vec<Option<f64>>>,
    /// Text above each group (e.g. the change in percent).
    pub(crate) notes: Vec<Option<String>>,
}

impl Chart for Bars {
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(self.cols) as u32;
        (420 * self.cols as u32, 60 + 320 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let area = ok(area.titled(&self.title, ("sans-serif", 22)))?;
        let rows = self.panels.len().div_ceil(self.cols);
        for (p, a) in self.panels.iter().zip(area.split_evenly((rows, self.cols))) {
            p.draw(&a)?;
        }
        Ok(())
    }
}

impl BarPanel {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let all: Vec<f64> = self
            .values
            .iter()
            .flatten()
            .flatten()
            .copied()
            .filter(|v| v.is_finite() && (!self.log || *v > 0.0))
            .collect();
        let Some(max) = all.iter().copied().reduce(f64::max) else {
            return Ok(());
        };
        let min = all.iter().copied().reduce(f64::min).unwrap_or(max);
        let (min, max) = match self.reference {
            Some((r, _)) => (min.min(r), max.max(r)),
            None => (min, max),
        };
        let tf = |v: f64| if self.log { v.log10() } else { v };
        // Log: whole decades, and room above for the legend. Linear (lengths): not from
        // zero, so that a change of 1 % is a visible step; room above for the legend.
        let (lo, hi) = if self.log {
            (tf(min).floor(), tf(max).ceil() + 0.6)
        } else {
            let lo = if self.from_zero { 0.0 } else { min * 0.97 };
            let hi = max + 0.45 * (max - lo);
            // All values equal (all zero collisions): still a scale.
            (lo, if hi > lo { hi } else { lo + 1.0 })
        };
        let n = self.groups.len();
        let mut chart = ok(ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(42)
            .y_label_area_size(58)
            .build_cartesian_2d(-0.5f64..n as f64 - 0.5, lo..hi))?;
        let groups = &self.groups;
        let log = self.log;
        ok(chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(WHITE)
            .x_labels(n)
            .x_label_formatter(&|x| {
                // Groups sit at the integers; other ticks get no label.
                if (x - x.round()).abs() < 1e-6 && *x >= 0.0 {
                    groups.get(x.round() as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .x_label_style(("sans-serif", 10))
            .y_labels(if log { log_ticks(lo, hi) } else { 8 })
            .y_label_formatter(&|y| if log { decade(*y) } else { tick(*y, lo, hi) })
            .y_desc(self.y_label.as_str())
            .draw())?;
        let width = 0.8 / self.series.len().max(1) as f64;
        for (s, (colour, name)) in self.series.iter().enumerate() {
            let colour = *colour;
            let bars = self.values.iter().enumerate().filter_map(|(g, v)| {
                let v = v.get(s).copied().flatten()?;
                let x0 = g as f64 - 0.4 + s as f64 * width;
                Some(Rectangle::new(
                    [(x0, lo), (x0 + width * 0.95, tf(v).max(lo))],
                    colour.filled(),
                ))
            });
            ok(chart.draw_series(bars))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], colour.filled())
                });
        }
        if let Some((r, name)) = &self.reference {
            let y = tf(*r);
            let style = ShapeStyle::from(RGBColor(200, 60, 40)).stroke_width(2);
            ok(chart.draw_series(std::iter::once(PathElement::new(
                vec![(-0.5, y), (n as f64 - 0.5, y)],
                style,
            ))))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 12, y)], style));
        }
        ok(chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .label_font(("sans-serif", 11))
            .draw())?;
        for (g, note) in self.notes.iter().enumerate() {
            let (Some(note), Some(top)) = (
                note,
                self.values[g]
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|v| !self.log || *v > 0.0)
                    .map(tf)
                    .reduce(f64::max),
            ) else {
                continue;
            };
            let style = TextStyle::from(("sans-serif", 11).into_font()).pos(
                plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Center,
                    plotters::style::text_anchor::VPos::Bottom,
                ),
            );
            ok(chart.draw_series(std::iter::once(Text::new(
                note.clone(),
                (g as f64, top + (hi - lo) * 0.01),
                style,
            ))))?;
        }
        Ok(())
    }
}

/// Horizontal box plots (median, quartiles, Tukey's whiskers, outliers as dots), one panel
/// per column.
pub(crate) struct Boxes {
    pub(crate) title: String,
    pub(crate) panels: Vec<BoxPanel>,
}

pub(crate) struct BoxPanel {
    pub(crate) title: String,
    pub(crate) x_label: String,
    pub(crate) log: bool,
    pub(crate) names: Vec<String>,
    pub(crate) samples: Vec<Vec<f64>>,
}

impl Chart for Boxes {
    fn size(&self) -> (u32, u32) {
        let n = self.panels.first().map_or(1, |p| p.names.len()) as u32;
        (520 * self.panels.len() as u32 + 60, 90 + 24 * n + 60)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let area = ok(area.titled(&self.title, ("sans-serif", 20)))?;
        for (p, a) in self
            .panels
            .iter()
            .zip(area.split_evenly((1, self.panels.len())))
        {
            p.draw(&a)?;
        }
        Ok(())
    }
}

impl BoxPanel {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let tf = |v: f64| if self.log { v.log10() } else { v };
        let data: Vec<Vec<f64>> = self
            .samples
            .iter()
            .map(|s| {
                s.iter()
                    .copied()
                    .filter(|v| v.is_finite() && (!self.log || *v > 0.0))
                    .map(tf)
                    .collect()
            })
            .collect();
        let all: Vec<f64> = data.iter().flatten().copied().collect();
        let (Some(min), Some(max)) = (
            all.iter().copied().reduce(f64::min),
            all.iter().copied().reduce(f64::max),
        ) else {
            return Ok(());
        };
        // Log: whole decades, so the ticks land on 1, 10, 100.
        let (lo, hi) = if self.log {
            (min.floor(), max.ceil().max(min.floor() + 1.0))
        } else {
            let pad = ((max - min) * 0.05).max(0.005);
            (min - pad, max + pad)
        };
        let n = self.names.len();
        // Planner `i` sits at y = n - 1 - i (the first on top).
        let mut chart = ok(ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(130)
            .build_cartesian_2d(lo..hi, -0.5f64..n as f64 - 0.5))?;
        let names = &self.names;
        let log = self.log;
        ok(chart
            .configure_mesh()
            .disable_y_mesh()
            .light_line_style(WHITE)
            .y_labels(n)
            .y_label_formatter(&|y| {
                let k = y.round();
                if (y - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < n {
                    names[n - 1 - k as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_label_style(("sans-serif", 11))
            .x_labels(if log { log_ticks(lo, hi) } else { 8 })
            .x_label_formatter(&|x| if log { decade(*x) } else { tick(*x, lo, hi) })
            .x_desc(self.x_label.as_str())
            .draw())?;
        let colour = RGBColor(40, 80, 160);
        for (i, d) in data.iter().enumerate() {
            let mut v = d.clone();
            let (Some(q1), Some(q2), Some(q3)) = (
                quantile(&mut v, 0.25),
                quantile(&mut v, 0.5),
                quantile(&mut v, 0.75),
            ) else {
                continue;
            };
            // Tukey's whiskers: the furthest samples within 1.5 IQR of the box.
            let iqr = q3 - q1;
            let inside = |x: &&f64| **x >= q1 - 1.5 * iqr && **x <= q3 + 1.5 * iqr;
            let wl = v.iter().filter(inside).copied().fold(q1, f64::min);
            let wh = v.iter().filter(inside).copied().fold(q3, f64::max);
            let y = (n - 1 - i) as f64;
            let h = 0.28;
            let style = ShapeStyle::from(colour).stroke_width(1);
            let mut shapes: Vec<DynElement<'static, DB, (f64, f64)>> = vec![
                Rectangle::new([(q1, y - h), (q3, y + h)], colour.mix(0.15).filled()).into_dyn(),
                Rectangle::new([(q1, y - h), (q3, y + h)], style).into_dyn(),
                PathElement::new(vec![(q2, y - h), (q2, y + h)], style.stroke_width(2)).into_dyn(),
                PathElement::new(vec![(wl, y), (q1, y)], style).into_dyn(),
                PathElement::new(vec![(q3, y), (wh, y)], style).into_dyn(),
                PathElement::new(vec![(wl, y - h / 2.0), (wl, y + h / 2.0)], style).into_dyn(),
                PathElement::new(vec![(wh, y - h / 2.0), (wh, y + h / 2.0)], style).into_dyn(),
            ];
            // Every sample as a dot, spread over the box's height in a fixed pattern so that
            // equal values stay apart (outliers are the dots beyond the whiskers).
            for (k, x) in d.iter().enumerate() {
                let jitter = ((k * 37) % 11) as f64 / 10.0 - 0.5;
                shapes.push(
                    Circle::new(
                        (*x, y + jitter * h * 1.4),
                        2,
                        RGBColor(200, 90, 30).mix(0.6).filled(),
                    )
                    .into_dyn(),
                );
            }
            ok(chart.draw_series(shapes))?;
        }
        Ok(())
    }
}
