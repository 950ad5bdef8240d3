//! Pictures of a run (`plotters`; PNG, SVG and animated GIF): the map, both trees, the
//! planned path, the agent's trail, the dynamic obstacles, the start, the goals numbered from
//! 1 with the active one ringed, the joining segment of a meet (the paper's Fig. 7b), a title
//! (planner, map, seed, moment), a legend and a scale bar.
//!
//! A [`Scene`] is a snapshot taken from the planner (owned points, so a picture can be drawn
//! after the planner moved on, and the reverse tree kept from before a meet cleared it).

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use bi_am_rrt::tree::Tree;
use bi_am_rrt::{Circle, OccupancyGrid, Point};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Walls.
const WALL: RGBColor = RGBColor(45, 45, 45);
/// Forward tree edges.
pub const FORWARD: RGBColor = RGBColor(140, 170, 230);
/// Reverse tree edges.
pub const REVERSE: RGBColor = RGBColor(120, 200, 120);
/// The planned path.
pub const PATH: RGBColor = RGBColor(215, 30, 30);
/// The agent's trail.
pub const TRAIL: RGBColor = RGBColor(240, 140, 0);
/// Dynamic obstacles.
pub const OBSTACLE: RGBColor = RGBColor(20, 20, 20);
/// The joining segment of a meet.
pub const MEET: RGBColor = RGBColor(200, 0, 200);
/// Start and goals.
const START: RGBColor = RGBColor(0, 140, 60);
const GOAL: RGBColor = RGBColor(30, 60, 200);

/// Width of the legend column, in pixels.
const LEGEND_PX: u32 = 190;
/// Height of the title bar, in pixels.
const TITLE_PX: u32 = 34;

/// Everything a picture shows, as owned points.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Title line (planner, map, seed, moment).
    pub title: String,
    /// Forward tree edges (parent, child).
    pub forward: Vec<[Point; 2]>,
    /// Reverse tree edges.
    pub reverse: Vec<[Point; 2]>,
    /// The planned path, root first.
    pub path: Vec<Point>,
    /// Where the agent has been.
    pub trail: Vec<Point>,
    /// Dynamic obstacles present.
    pub circles: Vec<Circle>,
    /// The start.
    pub start: Point,
    /// Every goal of the scenario, in order.
    pub goals: Vec<Point>,
    /// Index of the goal being planned for.
    pub active: Option<usize>,
    /// The agent.
    pub agent: Option<Point>,
    /// The joining segment of a meet.
    pub meet: Option<[Point; 2]>,
}

/// The edges of a tree.
pub fn edges<const N: usize>(t: &Tree<N>) -> Vec<[Point; 2]> {
    t.ids()
        .filter_map(|id| Some([t.position(t.parent(id)?)?, t.position(id)?]))
        .collect()
}

/// A plotters result as an `anyhow` one.
pub(crate) fn ok<T, E: std::fmt::Debug>(r: std::result::Result<T, E>) -> Result<T> {
    r.map_err(|e| anyhow!("drawing: {e:?}"))
}

/// Registers the embedded DejaVu Sans as `sans-serif` (no system fonts needed).
pub fn fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A "nice" length for the scale bar: 1, 2 or 5 times a power of ten, about a fifth of `w`.
fn nice_length(w: f64) -> f64 {
    let target = w / 5.0;
    let p = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * p)
        .find(|l| *l <= target)
        .unwrap_or(p)
}

/// Draws pictures of one map at a fixed size.
pub struct Painter<'g> {
    grid: OccupancyGrid<'g>,
    /// Pixels per metre.
    scale: f64,
    map_px: (u32, u32),
    /// Wall rectangles (runs of occupied cells along each row), in metres.
    walls: Vec<[(f64, f64); 2]>,
}

impl<'g> Painter<'g> {
    /// A painter for `grid`, about `target_px` pixels wide (the map part).
    pub fn new(grid: OccupancyGrid<'g>, target_px: u32) -> Self {
        let (wm, hm) = (f64::from(grid.width_m()), f64::from(grid.height_m()));
        let scale = (f64::from(target_px) / wm).max(0.5);
        let cell = f64::from(grid.cell_size());
        let mut walls = Vec::new();
        for r in 0..grid.rows() {
            let mut c = 0;
            while c < grid.cols() {
                if grid.is_occupied(c, r) {
                    let c0 = c;
                    while c < grid.cols() && grid.is_occupied(c, r) {
                        c += 1;
                    }
                    walls.push([
                        (f64::from(c0) * cell, f64::from(r) * cell),
                        (f64::from(c) * cell, f64::from(r + 1) * cell),
                    ]);
                } else {
                    c += 1;
                }
            }
        }
        Self {
            grid,
            scale,
            map_px: ((wm * scale).ceil() as u32, (hm * scale).ceil() as u32),
            walls,
        }
    }

    /// Picture size in pixels (map, legend column, title bar).
    pub fn size(&self) -> (u32, u32) {
        (
            self.map_px.0 + LEGEND_PX,
            (self.map_px.1 + TITLE_PX).max(TITLE_PX + 330),
        )
    }

    fn px(&self, p: Point) -> (i32, i32) {
        (
            (f64::from(p.x) * self.scale).round() as i32,
            (f64::from(p.y) * self.scale).round() as i32,
        )
    }

    /// Draws `scene` on `root` (of [`Painter::size`]).
    pub fn draw<DB: DrawingBackend>(
        &self,
        scene: &Scene,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<()> {
        fonts();
        ok(root.fill(&WHITE))?;
        let (title, rest) = root.split_vertically(TITLE_PX);
        ok(title.draw(&Text::new(
            scene.title.clone(),
            (8, 8),
            ("sans-serif", 17).into_font(),
        )))?;
        let (map, legend) = rest.split_horizontally(self.map_px.0);
        let map = map.shrink((0, 0), self.map_px);
        let line = |c: RGBColor, w: u32| ShapeStyle::from(c).stroke_width(w);
        // Map.
        for [a, b] in &self.walls {
            let p = |(x, y): (f64, f64)| ((x * self.scale) as i32, (y * self.scale) as i32);
            ok(map.draw(&Rectangle::new([p(*a), p(*b)], WALL.filled())))?;
        }
        ok(map.draw(&Rectangle::new(
            [(0, 0), (self.map_px.0 as i32 - 1, self.map_px.1 as i32 - 1)],
            line(BLACK, 1),
        )))?;
        // Trees, path, trail.
        for (edges, colour) in [(&scene.forward, FORWARD), (&scene.reverse, REVERSE)] {
            for [a, b] in edges.iter() {
                ok(map.draw(&PathElement::new(
                    vec![self.px(*a), self.px(*b)],
                    line(colour, 1),
                )))?;
            }
        }
        if scene.trail.len() > 1 {
            let pts: Vec<_> = scene.trail.iter().map(|p| self.px(*p)).collect();
            ok(map.draw(&PathElement::new(pts, line(TRAIL, 3))))?;
        }
        if scene.path.len() > 1 {
            let pts: Vec<_> = scene.path.iter().map(|p| self.px(*p)).collect();
            ok(map.draw(&PathElement::new(pts, line(PATH, 2))))?;
        }
        // Dynamic obstacles over the path (a path crossing one shows through).
        for c in &scene.circles {
            let r = (f64::from(c.radius) * self.scale).round().max(2.0) as i32;
            ok(map.draw(&plotters::element::Circle::new(
                self.px(c.center),
                r,
                OBSTACLE.mix(0.75).filled(),
            )))?;
            ok(map.draw(&plotters::element::Circle::new(
                self.px(c.center),
                r + 2,
                line(PATH, 1),
            )))?;
        }
        if let Some([a, b]) = scene.meet {
            ok(map.draw(&PathElement::new(
                vec![self.px(a), self.px(b)],
                line(MEET, 4),
            )))?;
            for p in [a, b] {
                ok(map.draw(&plotters::element::Circle::new(
                    self.px(p),
                    4,
                    MEET.filled(),
                )))?;
            }
        }
        // Start, goals (numbered from 1; the active one ringed), agent.
        let start_style = TextStyle::from(("sans-serif", 13).into_font()).color(&START);
        let goal_style = TextStyle::from(("sans-serif", 13).into_font()).color(&GOAL);
        let label = |s: String, at: (i32, i32), style: &TextStyle<'static>| {
            Text::new(s, (at.0 + 7, at.1 - 7), style.clone())
        };
        ok(map.draw(&plotters::element::Circle::new(
            self.px(scene.start),
            5,
            START.filled(),
        )))?;
        ok(map.draw(&label("S".into(), self.px(scene.start), &start_style)))?;
        for (i, g) in scene.goals.iter().enumerate() {
            let at = self.px(*g);
            ok(map.draw(&plotters::element::Circle::new(at, 4, GOAL.filled())))?;
            if scene.active == Some(i) {
                ok(map.draw(&plotters::element::Circle::new(at, 9, line(PATH, 2))))?;
            }
            ok(map.draw(&label(format!("{}", i + 1), at, &goal_style)))?;
        }
        if let Some(a) = scene.agent {
            ok(map.draw(&plotters::element::Circle::new(
                self.px(a),
                5,
                TRAIL.filled(),
            )))?;
            ok(map.draw(&plotters::element::Circle::new(
                self.px(a),
                5,
                line(BLACK, 1),
            )))?;
        }
        // Scale bar, bottom left, on a white box.
        let wm = f64::from(self.grid.width_m());
        let len = nice_length(wm);
        let bar = (len * self.scale).round() as i32;
        let (x0, y0) = (10, self.map_px.1 as i32 - 14);
        ok(map.draw(&Rectangle::new(
            [(x0 - 5, y0 - 22), (x0 + bar + 5, y0 + 8)],
            WHITE.mix(0.85).filled(),
        )))?;
        ok(map.draw(&Rectangle::new(
            [(x0, y0 - 3), (x0 + bar, y0 + 3)],
            BLACK.filled(),
        )))?;
        ok(map.draw(&Text::new(
            format!("{} m", len),
            (x0 + bar / 2, y0 - 6),
            TextStyle::from(("sans-serif", 13).into_font())
                .pos(Pos::new(HPos::Center, VPos::Bottom)),
        )))?;
        // Legend.
        let entries: [(&str, Swatch); 10] = [
            ("forward tree", Swatch::Line(FORWARD, 2)),
            ("reverse tree", Swatch::Line(REVERSE, 2)),
            ("planned path", Swatch::Line(PATH, 2)),
            ("agent's trail", Swatch::Line(TRAIL, 3)),
            ("meet (joining segment)", Swatch::Line(MEET, 4)),
            ("dynamic obstacle", Swatch::Disc(OBSTACLE, 6)),
            ("start S", Swatch::Disc(START, 5)),
            ("agent", Swatch::Disc(TRAIL, 5)),
            ("goals 1..n, active ringed", Swatch::Disc(GOAL, 4)),
            ("wall", Swatch::Square(WALL)),
        ];
        for (k, (name, sw)) in entries.iter().enumerate() {
            let y = 14 + 24 * k as i32;
            match *sw {
                Swatch::Line(c, w) => {
                    ok(legend.draw(&PathElement::new(vec![(10, y), (34, y)], line(c, w))))?
                }
                Swatch::Disc(c, r) => {
                    ok(legend.draw(&plotters::element::Circle::new((22, y), r, c.filled())))?
                }
                Swatch::Square(c) => {
                    ok(legend.draw(&Rectangle::new([(14, y - 7), (30, y + 7)], c.filled())))?
                }
            }
            ok(legend.draw(&Text::new(
                name.to_string(),
                (42, y),
                TextStyle::from(("sans-serif", 12).into_font())
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            )))?;
        }
        let cell = self.grid.cell_size();
        ok(legend.draw(&Text::new(
            format!(
                "{} x {} cells of {} m",
                self.grid.cols(),
                self.grid.rows(),
                cell
            ),
            (10, 14 + 24 * entries.len() as i32),
            TextStyle::from(("sans-serif", 11).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
        )))?;
        Ok(())
    }

    /// Writes `scene` as a PNG.
    pub fn png(&self, scene: &Scene, path: &Path) -> Result<()> {
        let (w, h) = self.size();
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            self.draw(scene, &root)?;
            ok(root.present())?;
        }
        image::RgbImage::from_raw(w, h, buf)
            .context("image buffer")?
            .save(path)
            .with_context(|| format!("{}", path.display()))
    }

    /// Writes `scene` as an SVG.
    pub fn svg(&self, scene: &Scene, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size()).into_drawing_area();
        self.draw(scene, &root)?;
        ok(root.present())
    }
}

/// A legend swatch.
#[derive(Clone, Copy)]
enum Swatch {
    Line(RGBColor, u32),
    Disc(RGBColor, i32),
    Square(RGBColor),
}

/// An animated GIF of a run, one frame per scene added (frames rendered with plotters,
/// encoded with `image`'s GIF encoder).
pub struct Animation<'a, 'g> {
    painter: &'a Painter<'g>,
    encoder: image::codecs::gif::GifEncoder<std::io::BufWriter<std::fs::File>>,
    delay_ms: u32,
    /// Frames written.
    pub frames: u32,
}

impl<'a, 'g> Animation<'a, 'g> {
    /// Starts `path` with `delay_ms` between frames, looping.
    pub fn new(painter: &'a Painter<'g>, path: &Path, delay_ms: u32) -> Result<Self> {
        let file = std::fs::File::create(path).with_context(|| format!("{}", path.display()))?;
        let mut encoder =
            image::codecs::gif::GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        encoder.set_repeat(image::codecs::gif::Repeat::Infinite)?;
        Ok(Self {
            painter,
            encoder,
            delay_ms,
            frames: 0,
        })
    }

    /// Adds a frame.
    pub fn frame(&mut self, scene: &Scene) -> Result<()> {
        let (w, h) = self.painter.size();
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            self.painter.draw(scene, &root)?;
            ok(root.present())?;
        }
        let rgb = image::RgbImage::from_raw(w, h, buf).context("image buffer")?;
        let rgba = image::DynamicImage::ImageRgb8(rgb).into_rgba8();
        let delay = image::Delay::from_numer_denom_ms(self.delay_ms, 1);
        self.encoder
            .encode_frame(image::Frame::from_parts(rgba, 0, 0, delay))?;
        self.frames += 1;
        Ok(())
    }
}
