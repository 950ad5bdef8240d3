//! Pictures of a run (`plotters`; PNG, SVG and animated GIF): the map, both trees, the
//! planned path, the agent's trail, the dynamic obstacles, the start, the goals numbered from
//! 1 with the active one ringed, the joining segment of a meet (the paper's Fig. 7b), a title
//! (planner, map, seed, moment), a legend and a scale bar.
//!
//! A [`Scene`] is a snapshot taken from the planner (owned points, so a picture can be drawn
//! after the planner moved on, and the reverse tree kept from before a meet cleared it).

pub mod chart;

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use bi_am_rrt::tree::Tree;
use bi_am_rrt::{Circle, OccupancyGrid, Point};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Walls.
const WALL: RGBColor = RGBColor(45, 45, 45);
/// The cells a robot body's disc cannot enter (the inflated margin), faintly.
const MARGIN: RGBColor = RGBColor(215, 215, 215);
/// Forward tree edges.
pub const FORWARD: RGBColor = RGBColor(140, 170, 230);
/// Reverse tree edges.
pub const REVERSE: RGBColor = RGBColor(120, 200, 120);
/// The planned path.
pub const PATH: RGBColor = RGBColor(215, 30, 30);
/// The agent's trail.
pub const TRAIL: RGBColor = RGBColor(240, 140, 0);
/// Dynamic obstacles (their own colour: not the walls').
pub const OBSTACLE: RGBColor = RGBColor(0, 150, 160);
/// The agent (a ring).
pub const AGENT: RGBColor = RGBColor(230, 110, 0);
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

/// The runs of occupied cells along each row of `grid`, as rectangles in metres.
fn runs(grid: &OccupancyGrid<'_>) -> Vec<[(f64, f64); 2]> {
    let cell = f64::from(grid.cell_size());
    let mut out = Vec::new();
    for r in 0..grid.rows() {
        let mut c = 0;
        while c < grid.cols() {
            if grid.is_occupied(c, r) {
                let c0 = c;
                while c < grid.cols() && grid.is_occupied(c, r) {
                    c += 1;
                }
                out.push([
                    (f64::from(c0) * cell, f64::from(r) * cell),
                    (f64::from(c) * cell, f64::from(r + 1) * cell),
                ]);
            } else {
                c += 1;
            }
        }
    }
    out
}

/// Draws pictures of one map at a fixed size.
pub struct Painter<'g> {
    grid: OccupancyGrid<'g>,
    /// Pixels per metre.
    scale: f64,
    map_px: (u32, u32),
    /// Wall rectangles (runs of occupied cells along each row), in metres.
    walls: Vec<[(f64, f64); 2]>,
    /// The robot body's margin: rectangles of the inflated grid's runs, and the radius.
    margin: Vec<[(f64, f64); 2]>,
    radius: f64,
}

impl<'g> Painter<'g> {
    /// A painter for `grid`, about `target_px` pixels wide (the map part).
    pub fn new(grid: OccupancyGrid<'g>, target_px: u32) -> Self {
        let (wm, hm) = (f64::from(grid.width_m()), f64::from(grid.height_m()));
        let scale = (f64::from(target_px) / wm).max(0.5);
        Self {
            grid,
            scale,
            map_px: ((wm * scale).ceil() as u32, (hm * scale).ceil() as u32),
            walls: runs(&grid),
            margin: Vec::new(),
            radius: 0.0,
        }
    }

    /// A painter for a scenario's map, with its robot's body when it has one.
    pub fn for_scenario(sc: &'g crate::scenario::Scenario, target_px: u32) -> Self {
        Self::new(sc.map.grid(), target_px).with_body(&sc.reach_grid(), sc.robot_radius)
    }

    /// This painter for a robot of `radius` metres whose inflated grid is `space`: the
    /// margin the disc cannot enter is drawn faintly under the walls, and the agent as a
    /// disc of its radius (never smaller than the usual ring).
    pub fn with_body(mut self, space: &OccupancyGrid<'_>, radius: f32) -> Self {
        if radius > 0.0 {
            self.margin = runs(space);
            self.radius = f64::from(radius);
        }
        self
    }

    /// Picture size in pixels (map, legend column, title bar).
    pub fn size(&self) -> (u32, u32) {
        (
            self.map_px.0 + LEGEND_PX,
            // Room for the legend and the obstacle inset below it.
            (self.map_px.1 + TITLE_PX).max(TITLE_PX + 500),
        )
    }

    /// The whole map as a view.
    fn full_view(&self) -> View {
        View {
            x0: 0.0,
            y0: 0.0,
            x1: f64::from(self.grid.width_m()),
            y1: f64::from(self.grid.height_m()),
            scale: self.scale,
        }
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
        let full = self.full_view();
        self.draw_view(scene, &map, &full, true)?;
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
        // Legend: only what this picture shows.
        let mut entries: Vec<(&str, Swatch)> = Vec::new();
        let mut add = |shown: bool, name: &'static str, sw: Swatch| {
            if shown {
                entries.push((name, sw));
            }
        };
        add(
            !scene.forward.is_empty(),
            "forward tree",
            Swatch::Line(FORWARD, 2),
        );
        add(
            !scene.reverse.is_empty(),
            "reverse tree",
            Swatch::Line(REVERSE, 2),
        );
        add(scene.path.len() > 1, "planned path", Swatch::Line(PATH, 2));
        add(
            scene.trail.len() > 1,
            "agent's trail",
            Swatch::Line(TRAIL, 3),
        );
        add(
            scene.meet.is_some(),
            "meet (joining segment)",
            Swatch::Line(MEET, 4),
        );
        add(
            !scene.circles.is_empty(),
            "dynamic obstacle",
            Swatch::Disc(OBSTACLE, 6),
        );
        add(true, "start S", Swatch::Disc(START, 5));
        add(scene.agent.is_some(), "agent", Swatch::Ring(AGENT, 6));
        add(
            !scene.goals.is_empty(),
            "goals 1..n, active ringed",
            Swatch::Disc(GOAL, 4),
        );
        add(!self.walls.is_empty(), "wall", Swatch::Square(WALL));
        add(
            !self.margin.is_empty(),
            "no room for the robot",
            Swatch::Square(MARGIN),
        );
        let line = |c: RGBColor, w: u32| ShapeStyle::from(c).stroke_width(w);
        for (k, (name, sw)) in entries.iter().enumerate() {
            let y = 14 + 24 * k as i32;
            match *sw {
                Swatch::Line(c, w) => {
                    ok(legend.draw(&PathElement::new(vec![(10, y), (34, y)], line(c, w))))?
                }
                Swatch::Disc(c, r) => {
                    ok(legend.draw(&plotters::element::Circle::new((22, y), r, c.filled())))?
                }
                Swatch::Ring(c, r) => {
                    ok(legend.draw(&plotters::element::Circle::new((22, y), r, line(c, 3))))?
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
        let below = 14 + 24 * entries.len() as i32;
        ok(legend.draw(&Text::new(
            format!(
                "{} x {} cells of {} m",
                self.grid.cols(),
                self.grid.rows(),
                cell
            ),
            (10, below),
            TextStyle::from(("sans-serif", 11).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
        )))?;
        // The first dynamic obstacle, zoomed: where the detour is.
        if let Some(c) = scene.circles.first() {
            let side = i32::try_from(LEGEND_PX).unwrap_or(190) - 14;
            let top = below + 22;
            let (_, lh) = legend.dim_in_pixel();
            if top + side + 18 <= lh as i32 {
                let half = (f64::from(c.radius) * 2.5).max(4.0);
                let (cx, cy) = (f64::from(c.center.x), f64::from(c.center.y));
                let view = View {
                    x0: cx - half,
                    y0: cy - half,
                    x1: cx + half,
                    y1: cy + half,
                    scale: f64::from(side) / (2.0 * half),
                };
                ok(legend.draw(&Text::new(
                    format!("around the obstacle (x{:.0})", view.scale / self.scale),
                    (8, top - 8),
                    TextStyle::from(("sans-serif", 11).into_font())
                        .pos(Pos::new(HPos::Left, VPos::Center)),
                )))?;
                let inset = legend.shrink((7, top), (side as u32, side as u32));
                ok(inset.fill(&WHITE))?;
                self.draw_view(scene, &inset, &view, false)?;
                ok(inset.draw(&Rectangle::new(
                    [(0, 0), (side - 1, side - 1)],
                    line(BLACK, 1),
                )))?;
            }
        }
        Ok(())
    }

    /// Draws the map layer of `scene` seen through `view` on `area` (whose pixel (0, 0) is
    /// the view's corner); everything outside the view is clipped. `labels`: S and goal
    /// numbers.
    fn draw_view<DB: DrawingBackend>(
        &self,
        scene: &Scene,
        area: &DrawingArea<DB, Shift>,
        view: &View,
        labels: bool,
    ) -> Result<()> {
        let line = |c: RGBColor, w: u32| ShapeStyle::from(c).stroke_width(w);
        let seg = |a: Point, b: Point, style: ShapeStyle| -> Result<()> {
            if let Some((p, q)) = view.clip(a, b) {
                ok(area.draw(&PathElement::new(vec![p, q], style)))?;
            }
            Ok(())
        };
        // Map: the body's margin faintly, the walls over it.
        for (rects, colour) in [(&self.margin, MARGIN), (&self.walls, WALL)] {
            for [a, b] in rects {
                let (x0, y0) = (a.0.max(view.x0), a.1.max(view.y0));
                let (x1, y1) = (b.0.min(view.x1), b.1.min(view.y1));
                if x0 < x1 && y0 < y1 {
                    ok(area.draw(&Rectangle::new(
                        [view.px_f(x0, y0), view.px_f(x1, y1)],
                        colour.filled(),
                    )))?;
                }
            }
        }
        let (w, h) = view.px_f(view.x1, view.y1);
        ok(area.draw(&Rectangle::new([(0, 0), (w - 1, h - 1)], line(BLACK, 1))))?;
        // Trees, path, trail.
        for (edges, colour) in [(&scene.forward, FORWARD), (&scene.reverse, REVERSE)] {
            for [a, b] in edges.iter() {
                seg(*a, *b, line(colour, 1))?;
            }
        }
        for w in scene.trail.windows(2) {
            seg(w[0], w[1], line(TRAIL, 3))?;
        }
        for w in scene.path.windows(2) {
            seg(w[0], w[1], line(PATH, 2))?;
        }
        // Dynamic obstacles over the path (a path crossing one shows through), in their own
        // colour with a dark edge.
        for c in &scene.circles {
            if !view.holds(c.center, f64::from(c.radius)) {
                continue;
            }
            let r = (f64::from(c.radius) * view.scale).round().max(2.0) as i32;
            let at = view.px(c.center);
            ok(area.draw(&plotters::element::Circle::new(
                at,
                r,
                OBSTACLE.mix(0.8).filled(),
            )))?;
            ok(area.draw(&plotters::element::Circle::new(at, r, line(BLACK, 1))))?;
        }
        if let Some([a, b]) = scene.meet {
            seg(a, b, line(MEET, 4))?;
            for p in [a, b] {
                if view.holds(p, 0.0) {
                    ok(area.draw(&plotters::element::Circle::new(
                        view.px(p),
                        4,
                        MEET.filled(),
                    )))?;
                }
            }
        }
        // The agent first, as a ring: S and the goals stay visible under it.
        if let Some(a) = scene.agent
            && view.holds(a, 0.0)
        {
            // A robot with a body: its disc to scale (translucent), under the usual ring.
            let body_px = (self.radius * view.scale).round() as i32;
            if self.radius > 0.0 {
                ok(area.draw(&plotters::element::Circle::new(
                    view.px(a),
                    body_px.max(1),
                    AGENT.mix(0.35).filled(),
                )))?;
            }
            ok(area.draw(&plotters::element::Circle::new(
                view.px(a),
                7.max(body_px),
                line(AGENT, 3),
            )))?;
        }
        let start_style = TextStyle::from(("sans-serif", 13).into_font()).color(&START);
        let goal_style = TextStyle::from(("sans-serif", 13).into_font()).color(&GOAL);
        let label = |s: String, at: (i32, i32), style: &TextStyle<'static>| {
            Text::new(s, (at.0 + 7, at.1 - 7), style.clone())
        };
        if view.holds(scene.start, 0.0) {
            let at = view.px(scene.start);
            ok(area.draw(&plotters::element::Circle::new(at, 5, START.filled())))?;
            if labels {
                ok(area.draw(&label("S".into(), at, &start_style)))?;
            }
        }
        for (i, g) in scene.goals.iter().enumerate() {
            if !view.holds(*g, 0.0) {
                continue;
            }
            let at = view.px(*g);
            ok(area.draw(&plotters::element::Circle::new(at, 4, GOAL.filled())))?;
            if scene.active == Some(i) {
                ok(area.draw(&plotters::element::Circle::new(at, 9, line(PATH, 2))))?;
            }
            if labels {
                ok(area.draw(&label(format!("{}", i + 1), at, &goal_style)))?;
            }
        }
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
    Ring(RGBColor, i32),
    Square(RGBColor),
}

/// A rectangle of the map (metres) drawn at `scale` pixels per metre from its corner.
struct View {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    scale: f64,
}

impl View {
    fn px_f(&self, x: f64, y: f64) -> (i32, i32) {
        (
            ((x - self.x0) * self.scale).round() as i32,
            ((y - self.y0) * self.scale).round() as i32,
        )
    }

    fn px(&self, p: Point) -> (i32, i32) {
        self.px_f(f64::from(p.x), f64::from(p.y))
    }

    /// Whether the disc of `r` around `p` lies wholly in the view.
    fn holds(&self, p: Point, r: f64) -> bool {
        let (x, y) = (f64::from(p.x), f64::from(p.y));
        x - r >= self.x0 && x + r <= self.x1 && y - r >= self.y0 && y + r <= self.y1
    }

    /// The part of segment `a`-`b` inside the view, in pixels (Liang-Barsky).
    fn clip(&self, a: Point, b: Point) -> Option<((i32, i32), (i32, i32))> {
        let (ax, ay) = (f64::from(a.x), f64::from(a.y));
        let (dx, dy) = (f64::from(b.x) - ax, f64::from(b.y) - ay);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-dx, ax - self.x0),
            (dx, self.x1 - ax),
            (-dy, ay - self.y0),
            (dy, self.y1 - ay),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let t = q / p;
                if p < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
            }
        }
        (t0 <= t1).then(|| {
            (
                self.px_f(ax + t0 * dx, ay + t0 * dy),
                self.px_f(ax + t1 * dx, ay + t1 * dy),
            )
        })
    }
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
