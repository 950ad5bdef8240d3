//! Maps and scenarios: PNG occupancy maps (read with the reference's rule), scenario files in
//! the form of `shared/maps/scenarios.toml`, and the core's built-in scenarios.
//!
//! PNG rule (the public AM-RRT* release's): every pixel is converted to grey as PIL's "L" mode
//! does, `(19595 R + 38470 G + 7471 B + 0x8000) >> 16`; a pixel is an obstacle when its grey
//! value is below the mean grey value of the whole image. One pixel is one cell; `x` is the
//! column and `y` the row from the top.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bi_am_rrt::Point;
use bi_am_rrt::builtin;
use bi_am_rrt::map::{OccupancyGrid, pack_grid};
use serde::Deserialize;

/// An occupancy grid that owns its bits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OwnedGrid {
    /// Columns.
    pub width: u16,
    /// Rows.
    pub height: u16,
    /// Cell side in metres (bit-exact `f32`).
    pub cell_bits: u32,
    /// Packed cells (layout of `bi_am_rrt::map`).
    pub bits: Vec<u8>,
}

impl OwnedGrid {
    /// A grid of `width x height` cells of `cell` metres from `occupied(col, row)`.
    pub fn from_fn(
        width: u16,
        height: u16,
        cell: f32,
        occupied: impl FnMut(u16, u16) -> bool,
    ) -> Result<Self> {
        let mut bits = vec![0u8; OccupancyGrid::bytes_needed(width, height)];
        pack_grid(&mut bits, width, height, occupied).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(Self {
            width,
            height,
            cell_bits: cell.to_bits(),
            bits,
        })
    }

    /// The core's view of the grid.
    pub fn grid(&self) -> OccupancyGrid<'_> {
        OccupancyGrid::new(
            &self.bits,
            self.width,
            self.height,
            f32::from_bits(self.cell_bits),
        )
        .expect("an OwnedGrid is valid by construction")
    }

    /// Copies a core grid.
    pub fn from_grid(g: &OccupancyGrid<'_>) -> Self {
        let n = OccupancyGrid::bytes_needed(g.cols(), g.rows());
        Self {
            width: g.cols(),
            height: g.rows(),
            cell_bits: g.cell_size().to_bits(),
            bits: g.bits()[..n].to_vec(),
        }
    }
}

/// PIL "L" grey value of an RGB pixel.
pub fn pil_grey(r: u8, g: u8, b: u8) -> u8 {
    ((19595 * r as u32 + 38470 * g as u32 + 7471 * b as u32 + 0x8000) >> 16) as u8
}

/// Reads a PNG map with the mean-threshold rule (module docs), 1 m per pixel.
pub fn load_png(path: &Path) -> Result<OwnedGrid> {
    let img = image::open(path)
        .with_context(|| format!("reading map {}", path.display()))?
        .to_rgb8();
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 || w > u16::MAX as u32 || h > u16::MAX as u32 {
        bail!("map {} has unusable size {w} x {h}", path.display());
    }
    let grey: Vec<u8> = img.pixels().map(|p| pil_grey(p[0], p[1], p[2])).collect();
    let mean = grey.iter().map(|&v| v as f64).sum::<f64>() / grey.len() as f64;
    OwnedGrid::from_fn(w as u16, h as u16, 1.0, |c, r| {
        (grey[r as usize * w as usize + c as usize] as f64) < mean
    })
}

/// One scenario: a map, a start, goals and the connection distance.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name (the TOML table name, or the built-in name).
    pub name: String,
    /// The map.
    pub map: OwnedGrid,
    /// Where the map came from (a file path or `builtin:NAME`).
    pub source: String,
    /// Start position.
    pub start: Point,
    /// Goals in order.
    pub goals: Vec<Point>,
    /// Connection distance of the two trees.
    pub sigma: f32,
}

#[derive(Deserialize)]
struct Entry {
    file: PathBuf,
    #[serde(default)]
    size_m: Option<[f32; 2]>,
    #[serde(default = "default_sigma")]
    sigma_m: f32,
    start: [f32; 2],
    goals: Vec<[f32; 2]>,
}

fn default_sigma() -> f32 {
    30.0
}

/// Reads a scenario file; map paths are relative to it. `only` keeps the named scenarios (in
/// the file's order); an unknown name is an error.
pub fn load_scenarios(path: &Path, only: Option<&[String]>) -> Result<Vec<Scenario>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let table: toml::Table =
        toml::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    if let Some(names) = only {
        for n in names {
            if !table.contains_key(n) {
                bail!("scenario {n:?} is not in {}", path.display());
            }
        }
    }
    let mut out = Vec::new();
    for (name, value) in table {
        if only.is_some_and(|names| !names.contains(&name)) {
            continue;
        }
        let e: Entry = value
            .try_into()
            .with_context(|| format!("scenario {name}"))?;
        let file = dir.join(&e.file);
        let map = load_png(&file)?;
        if let Some([w, h]) = e.size_m
            && (w != map.width as f32 || h != map.height as f32)
        {
            bail!(
                "scenario {name}: size_m {w} x {h} but the map is {} x {} cells",
                map.width,
                map.height
            );
        }
        let pt = |p: [f32; 2]| Point::new(p[0], p[1]);
        out.push(Scenario {
            name,
            map,
            source: file.display().to_string(),
            start: pt(e.start),
            goals: e.goals.into_iter().map(pt).collect(),
            sigma: e.sigma_m,
        });
    }
    Ok(out)
}

/// The core's built-in scenarios as host scenarios.
pub fn builtin_scenarios() -> Vec<Scenario> {
    builtin::ALL.iter().map(|s| builtin_scenario(s)).collect()
}

/// One built-in scenario.
pub fn builtin_scenario(s: &builtin::Scenario) -> Scenario {
    Scenario {
        name: s.name.to_string(),
        map: OwnedGrid::from_grid(&s.grid),
        source: format!("builtin:{}", s.name),
        start: s.start,
        goals: s.goals.to_vec(),
        sigma: s.sigma,
    }
}

/// The built-in scenario of this name.
pub fn builtin_by_name(name: &str) -> Result<Scenario> {
    builtin::by_name(name)
        .map(builtin_scenario)
        .with_context(|| {
            let names: Vec<_> = builtin::ALL.iter().map(|s| s.name).collect();
            format!("no built-in scenario {name:?} (have {names:?})")
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pil_grey_matches_pil() {
        assert_eq!(pil_grey(255, 255, 255), 255);
        assert_eq!(pil_grey(0, 0, 0), 0);
        // PIL: L = R * 299/1000 + G * 587/1000 + B * 114/1000, rounded.
        assert_eq!(pil_grey(255, 0, 0), 76);
        assert_eq!(pil_grey(0, 255, 0), 150);
        assert_eq!(pil_grey(0, 0, 255), 29);
    }

    #[test]
    fn builtins_round_trip() {
        let s = builtin_by_name("maze").unwrap();
        assert_eq!(
            s.map.grid().is_occupied(5, 12),
            builtin::MAZE.grid.is_occupied(5, 12)
        );
        assert!(builtin_by_name("nope").is_err());
    }
}
