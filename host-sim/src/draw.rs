//! Pictures: the map, both trees, the path, the agent's trail and the dynamic obstacles,
//! rendered to PNG.

use std::path::Path;

use anyhow::Result;
use bi_am_rrt::tree::Tree;
use bi_am_rrt::{Circle, OccupancyGrid, Point};
use image::{Rgb, RgbImage};
use imageproc::drawing::{draw_filled_circle_mut, draw_hollow_circle_mut, draw_line_segment_mut};

/// A picture of a map at `scale` pixels per metre.
pub struct Canvas {
    img: RgbImage,
    scale: f32,
}

const FREE: Rgb<u8> = Rgb([255, 255, 255]);
const WALL: Rgb<u8> = Rgb([40, 40, 40]);
/// Forward tree edges.
pub const FORWARD: Rgb<u8> = Rgb([150, 180, 235]);
/// Reverse tree edges.
pub const REVERSE: Rgb<u8> = Rgb([150, 215, 150]);
/// The planned path.
pub const PATH: Rgb<u8> = Rgb([220, 30, 30]);
/// The agent's trail.
pub const TRAIL: Rgb<u8> = Rgb([240, 140, 0]);
/// Dynamic obstacles.
pub const OBSTACLE: Rgb<u8> = Rgb([90, 90, 90]);

impl Canvas {
    /// A canvas showing `grid`, about `target_px` pixels wide.
    pub fn new(grid: &OccupancyGrid<'_>, target_px: u32) -> Self {
        let scale = (target_px as f32 / grid.width_m()).max(1.0);
        let (w, h) = (
            (grid.width_m() * scale) as u32,
            (grid.height_m() * scale) as u32,
        );
        let mut img = RgbImage::from_pixel(w, h, FREE);
        for (x, y, px) in img.enumerate_pixels_mut() {
            let p = Point::new((x as f32 + 0.5) / scale, (y as f32 + 0.5) / scale);
            if let Some((c, r)) = grid.cell_of(p)
                && grid.is_occupied(c, r)
            {
                *px = WALL;
            }
        }
        Self { img, scale }
    }

    fn px(&self, p: Point) -> (f32, f32) {
        (p.x * self.scale, p.y * self.scale)
    }

    /// A segment.
    pub fn line(&mut self, a: Point, b: Point, colour: Rgb<u8>) {
        let (pa, pb) = (self.px(a), self.px(b));
        draw_line_segment_mut(&mut self.img, pa, pb, colour);
    }

    /// A thick polyline.
    pub fn polyline(&mut self, pts: &[Point], colour: Rgb<u8>) {
        for w in pts.windows(2) {
            for (dx, dy) in [(0.0, 0.0), (0.6, 0.0), (0.0, 0.6), (-0.6, 0.0), (0.0, -0.6)] {
                let o = Point::new(dx / self.scale, dy / self.scale);
                self.line(w[0] + o, w[1] + o, colour);
            }
        }
    }

    /// Every edge of a tree.
    pub fn tree<const N: usize>(&mut self, t: &Tree<N>, colour: Rgb<u8>) {
        for id in t.ids() {
            if let (Some(p), Some(a)) = (t.parent(id).and_then(|p| t.position(p)), t.position(id)) {
                self.line(p, a, colour);
            }
        }
    }

    /// A filled disc of `radius_px` pixels.
    pub fn dot(&mut self, p: Point, radius_px: i32, colour: Rgb<u8>) {
        let (x, y) = self.px(p);
        draw_filled_circle_mut(&mut self.img, (x as i32, y as i32), radius_px, colour);
    }

    /// A dynamic obstacle.
    pub fn circle(&mut self, c: &Circle) {
        let (x, y) = self.px(c.center);
        let r = (c.radius * self.scale) as i32;
        draw_filled_circle_mut(&mut self.img, (x as i32, y as i32), r, OBSTACLE);
        draw_hollow_circle_mut(&mut self.img, (x as i32, y as i32), r, Rgb([0, 0, 0]));
    }

    /// Writes the PNG.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.img.save(path)?;
        Ok(())
    }
}
