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

/// The most cells a map may have (4096 x 4096): larger images are refused before they are
/// decoded, so a wrong file costs neither gigabytes nor minutes.
pub const MAX_MAP_CELLS: u64 = 4096 * 4096;

/// Reads a PNG map file with the mean-threshold rule (module docs); see [`decode_png`].
pub fn load_png(path: &Path) -> Result<OwnedGrid> {
    let bytes = read_image(path, image::ImageFormat::Png)?;
    decode_png(&bytes, &path.display().to_string())
}

/// Reads an image file whole once its header has given a size within [`MAX_MAP_CELLS`] (a
/// wrong file costs neither its gigabytes of reading nor their memory).
fn read_image(path: &Path, format: image::ImageFormat) -> Result<Vec<u8>> {
    let name = path.display();
    let file = std::fs::File::open(path).with_context(|| format!("reading map {name}"))?;
    let (w, h) = image::ImageReader::with_format(std::io::BufReader::new(file), format)
        .into_dimensions()
        .with_context(|| format!("reading the size of map {name}"))?;
    check_size(w, h, &name.to_string())?;
    std::fs::read(path).with_context(|| format!("reading map {name}"))
}

/// Refuses an empty image and one over [`MAX_MAP_CELLS`].
fn check_size(w: u32, h: u32, name: &str) -> Result<()> {
    if w == 0 || h == 0 {
        bail!("map {name} is empty ({w} x {h} pixels)");
    }
    if w as u64 * h as u64 > MAX_MAP_CELLS || w > u16::MAX as u32 || h > u16::MAX as u32 {
        bail!(
            "map {name} is {w} x {h} pixels: at most {MAX_MAP_CELLS} cells (4096 x 4096) are supported"
        );
    }
    Ok(())
}

/// Decodes a PNG map (named `name` in errors) with the mean-threshold rule (module docs), 1 m
/// per pixel. Refused: images over [`MAX_MAP_CELLS`] (checked from the header, before
/// decoding) and images of one dark grey level, which the rule would read as all free (a
/// uniform light image is an empty map).
pub fn decode_png(bytes: &[u8], name: &str) -> Result<OwnedGrid> {
    let (w, h, grey) = decode_grey(bytes, image::ImageFormat::Png, name)?;
    let mean = grey.iter().map(|&v| v as f64).sum::<f64>() / grey.len() as f64;
    if grey.iter().all(|&v| v == grey[0]) && grey[0] < 128 {
        bail!(
            "map {name} is a single dark grey level ({}): the mean-threshold rule would read it \
             as all free; draw free space light and obstacles dark",
            grey[0]
        );
    }
    OwnedGrid::from_fn(w, h, 1.0, |c, r| {
        (grey[r as usize * w as usize + c as usize] as f64) < mean
    })
}

/// Decodes an image to PIL "L" grey levels, row by row from the top, refusing images over
/// [`MAX_MAP_CELLS`] before decoding them.
fn decode_grey(
    bytes: &[u8],
    format: image::ImageFormat,
    name: &str,
) -> Result<(u16, u16, Vec<u8>)> {
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let (w, h) = reader()
        .into_dimensions()
        .with_context(|| format!("reading the size of map {name}"))?;
    check_size(w, h, name)?;
    let mut reader = reader();
    // Decoding buffers stay within the cap too (RGBA16 at most: 8 bytes a pixel).
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    limits.max_alloc = Some(MAX_MAP_CELLS * 8 + (1 << 20));
    reader.limits(limits);
    let img = reader
        .decode()
        .with_context(|| format!("decoding map {name}"))?
        .to_rgb8();
    let grey = img.pixels().map(|p| pil_grey(p[0], p[1], p[2])).collect();
    Ok((w as u16, h as u16, grey))
}

/// A map as a scenario file names it: the grid, and for a ROS map the frame its positions
/// are given in.
#[derive(Clone, Debug)]
pub struct MapFile {
    /// The grid (cell side from the file, or 1 m for a PNG until `resolution_m` says).
    pub grid: OwnedGrid,
    /// ROS map_server maps: the world position of the lower-left corner of the image
    /// (`origin` x, y). Positions in the scenario file are then in this frame, y up.
    pub ros_origin: Option<[f64; 2]>,
}

impl From<OwnedGrid> for MapFile {
    fn from(grid: OwnedGrid) -> Self {
        Self {
            grid,
            ros_origin: None,
        }
    }
}

/// The fields of a ROS map_server YAML file the loader reads (others are ignored).
#[derive(Deserialize)]
struct RosYaml {
    image: PathBuf,
    resolution: f32,
    #[serde(default)]
    origin: Option<Vec<f64>>,
    #[serde(default)]
    negate: Option<serde_yaml_ng::Value>,
    #[serde(default = "default_occupied")]
    occupied_thresh: f64,
    #[serde(default = "default_free")]
    free_thresh: f64,
    #[serde(default)]
    mode: Option<String>,
}

fn default_occupied() -> f64 {
    0.65
}

fn default_free() -> f64 {
    0.196
}

/// Reads a ROS map_server map: the YAML file and the image it names (PGM or PNG, relative to
/// it); see [`ros_map_from`].
pub fn load_ros_yaml(path: &Path) -> Result<MapFile> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let image: RosYaml =
        serde_yaml_ng::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let img = path.parent().unwrap_or(Path::new(".")).join(&image.image);
    let bytes = read_image(&img, ros_image_format(&image.image)?)
        .with_context(|| format!("the image of {}", path.display()))?;
    ros_map_from(&text, &bytes, &path.display().to_string())
}

/// The format of a ROS map's image from its name: PGM (or another PNM) or PNG.
fn ros_image_format(image: &Path) -> Result<image::ImageFormat> {
    let ext = image
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    Ok(match ext.as_deref() {
        Some("png") => image::ImageFormat::Png,
        Some("pgm" | "ppm" | "pnm" | "pbm") => image::ImageFormat::Pnm,
        _ => bail!("image {} is not a PGM or a PNG", image.display()),
    })
}

/// The cell sizes a map may have, in metres: 0.1 mm to 1 km. A ROS map is 0.01-0.1 m, a
/// benchmark grid 0.25-10 m; beyond this range a figure is a typing or unit error (the core
/// itself takes any finite size with a finite inverse and extent).
pub const RESOLUTION_RANGE: std::ops::RangeInclusive<f32> = 1.0e-4..=1.0e3;

/// Refuses a cell size outside [`RESOLUTION_RANGE`] (or not a number): `what` names where it
/// was written.
pub fn check_resolution(what: &str, r: f32) -> Result<()> {
    if !RESOLUTION_RANGE.contains(&r) {
        bail!(
            "{what} = {r} m: a cell size must be a number of metres from {} to {}",
            RESOLUTION_RANGE.start(),
            RESOLUTION_RANGE.end()
        );
    }
    Ok(())
}

/// A ROS map_server map from its YAML text and image bytes, with map_server's rule (mode
/// `trinary` or `scale`): a pixel of grey `v` has occupancy `p = (255 - v) / 255` (`v / 255`
/// with `negate: 1`); it is an obstacle when `p > occupied_thresh`, free when
/// `p < free_thresh`, and unknown between, which the planner treats as an obstacle. One pixel
/// is one cell of `resolution` metres; `origin` is the world pose of the lower-left pixel
/// (a yaw is refused), y up. Mode `raw` is refused.
pub fn ros_map_from(yaml: &str, image_bytes: &[u8], name: &str) -> Result<MapFile> {
    let y: RosYaml = serde_yaml_ng::from_str(yaml).with_context(|| format!("parsing {name}"))?;
    check_resolution(&format!("{name}: resolution"), y.resolution)?;
    let negate = match &y.negate {
        None => false,
        Some(serde_yaml_ng::Value::Bool(b)) => *b,
        Some(serde_yaml_ng::Value::Number(n)) if n.as_i64() == Some(0) => false,
        Some(serde_yaml_ng::Value::Number(n)) if n.as_i64() == Some(1) => true,
        Some(v) => bail!("{name}: negate {v:?} (must be 0 or 1)"),
    };
    if !(0.0..=1.0).contains(&y.free_thresh)
        || !(0.0..=1.0).contains(&y.occupied_thresh)
        || y.free_thresh > y.occupied_thresh
    {
        bail!(
            "{name}: free_thresh {} and occupied_thresh {} must lie in [0, 1], free <= occupied",
            y.free_thresh,
            y.occupied_thresh
        );
    }
    match y.mode.as_deref() {
        None | Some("trinary") | Some("scale") => {}
        Some(m) => bail!("{name}: mode {m:?} is not supported (trinary or scale)"),
    }
    let origin = y.origin.unwrap_or_else(|| vec![0.0, 0.0, 0.0]);
    let [ox, oy] = match origin[..] {
        [x, y] | [x, y, _] if x.is_finite() && y.is_finite() => [x, y],
        _ => bail!("{name}: origin {origin:?} (must be [x, y, yaw])"),
    };
    if origin.get(2).is_some_and(|yaw| *yaw != 0.0) {
        bail!(
            "{name}: origin yaw {} (rotated maps are not supported)",
            origin[2]
        );
    }
    let format = ros_image_format(&y.image).with_context(|| name.to_string())?;
    let (w, h, grey) = decode_grey(image_bytes, format, name)?;
    let occupied = |v: u8| {
        let p = if negate {
            f64::from(v) / 255.0
        } else {
            (255.0 - f64::from(v)) / 255.0
        };
        // Occupied, or unknown (between the thresholds): not free.
        p > y.occupied_thresh || p >= y.free_thresh
    };
    let grid = OwnedGrid::from_fn(w, h, y.resolution, |c, r| {
        occupied(grey[r as usize * w as usize + c as usize])
    })?;
    Ok(MapFile {
        grid,
        ros_origin: Some([ox, oy]),
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
    /// The connection distance of the two trees as the scenario states it, in metres (a
    /// file's `sigma_m`, a built-in's); `None`: the paper's 30 m, fitted to the map like the
    /// other lengths ([`Scenario::sigma`]).
    pub sigma_m: Option<f32>,
    /// The world pose of the map's lower-left corner when positions were given in a ROS map
    /// frame (y up); `None`: metres from the top-left corner, y down.
    pub ros_origin: Option<[f64; 2]>,
    /// Run the planners with Table 2's lengths in metres as printed instead of the lengths
    /// that follow the map ([`bi_am_rrt::Config::for_map`]; `--paper-lengths`).
    pub paper_lengths: bool,
    /// The robot's radius in metres (0: a point; the file's `robot_radius_m`, or
    /// `--robot-radius`): set it with [`Scenario::with_robot_radius`], which inflates the map.
    pub robot_radius: f32,
    /// The map inflated for the robot's disc by the cells rule ([`bi_am_rrt::map::inflate`])
    /// when the radius is not 0: the planner's fast test (its exact test reads the map).
    pub space: Option<OwnedGrid>,
    /// The cells where the disc has room (at the centre or the middle of a side:
    /// `bi_am_rrt::map::Live::is_occupied` with the body) when the radius is not 0: where it
    /// can go, to within a cell, for the metric tables, the exact optimum, OMPL and the check
    /// that every leg can be driven.
    pub reach: Option<OwnedGrid>,
    /// The clearance preference (`--clearance-margin`, `--clearance-weight`): the field of
    /// [`bi_am_rrt::clearance::clearance_field`] for the robot's radius, and the weight the
    /// planner's configuration gets. `None`: every edge costs its length (the paper's).
    pub clearance: Option<Clearance>,
}

/// A clearance preference ([`bi_am_rrt::clearance`]).
#[derive(Clone, Debug)]
pub struct Clearance {
    /// Metres beyond the body over which the cost falls to the length itself.
    pub margin: f32,
    /// [`bi_am_rrt::Config::clearance_weight`].
    pub weight: f32,
    /// A byte per cell, row-major.
    pub field: Vec<u8>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    file: PathBuf,
    #[serde(default)]
    size_m: Option<[f32; 2]>,
    /// Cell side of a PNG map in metres (default 1; a ROS map's YAML gives its own).
    #[serde(default)]
    resolution_m: Option<f32>,
    #[serde(default)]
    sigma_m: Option<f32>,
    /// The robot's radius in metres (default 0: a point).
    #[serde(default)]
    robot_radius_m: Option<f32>,
    /// A clearance preference: metres beyond the body (default: none).
    #[serde(default)]
    clearance_margin_m: Option<f32>,
    /// Its weight (default 1).
    #[serde(default)]
    clearance_weight: Option<f32>,
    start: [f32; 2],
    goals: Vec<[f32; 2]>,
}

/// The paper's `sigma` on its 100-200 m maps, scaled to other maps.
const PAPER_SIGMA_M: f32 = 30.0;

/// The name that stands for the built-in scenarios where a scenario file is expected.
pub const BUILTIN_SET: &str = "builtin";

/// Reads a scenario file; map paths are relative to it. `only` keeps the named scenarios (in
/// the file's order); an unknown name is an error. The path [`BUILTIN_SET`] (when no such file
/// exists) reads the built-in scenarios instead, small and paper-sized.
pub fn load_scenarios(path: &Path, only: Option<&[String]>) -> Result<Vec<Scenario>> {
    if path == Path::new(BUILTIN_SET) && !path.exists() {
        return builtin_set(only);
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let load = |file: &Path| -> Result<MapFile> {
        let path = dir.join(file);
        match path.extension().and_then(|e| e.to_str()) {
            Some("yaml" | "yml") => load_ros_yaml(&path),
            _ => load_png(&path).map(MapFile::from),
        }
    };
    let mut scenarios =
        scenarios_from_str(&text, load, only).with_context(|| format!("in {}", path.display()))?;
    for s in &mut scenarios {
        s.source = dir.join(&s.source).display().to_string();
    }
    Ok(scenarios)
}

/// Parses scenario-file text; `load_map(file)` reads the map a scenario names. Unknown keys,
/// missing fields and invalid scenarios ([`Scenario::validate`]) are errors. Positions are
/// metres from the map's top-left corner, y down (a PNG map), or in the map frame of a ROS
/// map (y up from its `origin`), and are converted to the former.
pub fn scenarios_from_str(
    text: &str,
    mut load_map: impl FnMut(&Path) -> Result<MapFile>,
    only: Option<&[String]>,
) -> Result<Vec<Scenario>> {
    let table: toml::Table = toml::from_str(text).context("parsing the scenario file")?;
    if let Some(names) = only {
        for n in names {
            if !table.contains_key(n) {
                bail!("scenario {n:?} is not in the file");
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
        let MapFile {
            grid: mut map,
            ros_origin,
        } = load_map(&e.file).with_context(|| format!("scenario {name}"))?;
        if let Some(r) = e.resolution_m {
            if ros_origin.is_some() {
                bail!("scenario {name}: resolution_m is for PNG maps; a ROS map's YAML gives it");
            }
            check_resolution(&format!("scenario {name}: resolution_m"), r)?;
            map.cell_bits = r.to_bits();
        }
        let cell = f32::from_bits(map.cell_bits);
        let (wm, hm) = (map.width as f32 * cell, map.height as f32 * cell);
        if let Some([w, h]) = e.size_m
            && ((w - wm).abs() > 1e-3 * wm || (h - hm).abs() > 1e-3 * hm)
        {
            bail!(
                "scenario {name}: size_m {w} x {h} but the map is {} x {} cells of {cell} m = {wm} x {hm} m",
                map.width,
                map.height
            );
        }
        // ROS maps: world (x, y up from the origin) to grid (from the top-left corner, y down).
        let pt = |p: [f32; 2]| match ros_origin {
            Some([ox, oy]) => Point::new(
                (f64::from(p[0]) - ox) as f32,
                (f64::from(hm) - (f64::from(p[1]) - oy)) as f32,
            ),
            None => Point::new(p[0], p[1]),
        };
        let sc = Scenario {
            ros_origin,
            ..Scenario::new(
                name,
                map,
                e.file.display().to_string(),
                pt(e.start),
                e.goals.into_iter().map(pt).collect(),
                e.sigma_m,
            )
        };
        let sc = sc.with_robot_radius(e.robot_radius_m.unwrap_or(0.0))?;
        let sc = match e.clearance_margin_m {
            Some(m) => sc.with_clearance(m, e.clearance_weight.unwrap_or(1.0))?,
            None => sc,
        };
        out.push(sc);
    }
    Ok(out)
}

impl Scenario {
    /// A scenario on `map` in the planner's frame (no ROS origin), for a point robot, with
    /// the lengths that follow the map and no clearance preference: what the loaders, the
    /// built-in maps and the tests start from.
    pub fn new(
        name: impl Into<String>,
        map: OwnedGrid,
        source: impl Into<String>,
        start: Point,
        goals: Vec<Point>,
        sigma_m: Option<f32>,
    ) -> Self {
        Self {
            name: name.into(),
            map,
            source: source.into(),
            start,
            goals,
            sigma_m,
            ros_origin: None,
            paper_lengths: false,
            robot_radius: 0.0,
            space: None,
            reach: None,
            clearance: None,
        }
    }

    /// The length scale the configurations get on this scenario: the map's
    /// ([`bi_am_rrt::config::length_scale`] of its larger side), or 1 (Table 2's metres) with
    /// `paper_lengths`.
    pub fn length_scale(&self) -> f32 {
        if self.paper_lengths {
            return 1.0;
        }
        let g = self.map.grid();
        bi_am_rrt::config::length_scale(g.width_m().max(g.height_m()))
    }

    /// The connection distance `sigma` the planners get here: the scenario's own
    /// ([`Scenario::sigma_m`]), else the paper's 30 m times [`Scenario::length_scale`].
    pub fn sigma(&self) -> f32 {
        self.sigma_m
            .unwrap_or_else(|| PAPER_SIGMA_M * self.length_scale())
    }

    /// A position of the planner's frame (metres from the top-left corner, y down) in the
    /// frame the scenario was written in: a ROS map's frame (y up from its origin) or the
    /// former.
    pub fn user_frame(&self, p: Point) -> [f64; 2] {
        match self.ros_origin {
            Some([ox, oy]) => {
                let hm = f64::from(self.map.height) * f64::from(f32::from_bits(self.map.cell_bits));
                [f64::from(p.x) + ox, hm - f64::from(p.y) + oy]
            }
            None => [f64::from(p.x), f64::from(p.y)],
        }
    }

    /// A position as the user wrote it, for messages: `(x, y)` in the scenario's frame,
    /// rounded to a millimetre.
    pub fn show(&self, p: Point) -> String {
        let [x, y] = self.user_frame(p);
        let r = |v: f64| (v * 1000.0).round() / 1000.0;
        format!("({}, {})", r(x), r(y))
    }

    /// Checks what a run needs: at least one goal, `sigma` finite and not negative, the start
    /// and every goal inside the map and free. Goals are numbered from 1, as in the output.
    pub fn validate(&self) -> Result<()> {
        let name = &self.name;
        if self.goals.is_empty() {
            bail!("scenario {name}: `goals` is empty (give at least one goal)");
        }
        if let Some(sigma) = self.sigma_m
            && !(sigma.is_finite() && sigma >= 0.0)
        {
            bail!("scenario {name}: sigma_m = {sigma} (must be finite and not negative)");
        }
        let map = self.planner_map::<0>()?;
        let body = if self.robot_radius > 0.0 {
            format!(" (a robot of radius {} m)", self.robot_radius)
        } else {
            String::new()
        };
        let check = |what: String, p: Point| {
            self.room(&map, p).map_err(|e| {
                // Where the disc would fit instead, when it is the body that does not.
                let near = match e {
                    bi_am_rrt::error::InputError::NoRoom => self
                        .nearest_room(&map, p)
                        .map(|q| {
                            format!(
                                "; the nearest position with room is {} ({:.3} m away)",
                                self.show(q),
                                p.dist(q)
                            )
                        })
                        .unwrap_or_default(),
                    _ => String::new(),
                };
                anyhow::anyhow!("scenario {name}: {what} {}: {e}{body}{near}", self.show(p))
            })
        };
        check("start".into(), self.start)?;
        for (i, g) in self.goals.iter().enumerate() {
            check(format!("goal {}", i + 1), *g)?;
        }
        if self.robot_radius > 0.0 {
            // A goal the disc cannot reach (a passage narrower than its diameter) is refused
            // here, with the leg named, rather than searched for in vain.
            let space = self.reach_grid();
            let parts = crate::metric::graph::components(&space);
            let part = |p: Point| {
                space
                    .cell_of(p)
                    .and_then(|(c, r)| parts[cell_at(&space, c, r)])
            };
            let mut from = ("the start".to_string(), self.start);
            for (i, &g) in self.goals.iter().enumerate() {
                if part(from.1) != part(g) {
                    bail!(
                        "scenario {name}: goal {} {} cannot be reached from {} {} by a robot of \
                         radius {} m: every way between them passes where the disc does not fit \
                         (a passage narrower than {} m); give a smaller --robot-radius",
                        i + 1,
                        self.show(g),
                        from.0,
                        self.show(from.1),
                        self.robot_radius,
                        2.0 * self.robot_radius
                    );
                }
                from = (format!("goal {}", i + 1), g);
            }
        }
        Ok(())
    }

    /// `map.check_point(p)`, and with a body also room in `p`'s cell of [`Scenario::reach`]
    /// (a position with room only in a corner of its cell, where no sample finds it, is one
    /// the metric tables cannot place: [`InputError::NoRoom`](bi_am_rrt::error::InputError)).
    fn room<const K: usize>(
        &self,
        map: &bi_am_rrt::Map<'_, K>,
        p: Point,
    ) -> Result<(), bi_am_rrt::error::InputError> {
        map.check_point(p)?;
        let Some(reach) = &self.reach else {
            return Ok(());
        };
        let g = reach.grid();
        match g.cell_of(p) {
            Some((c, r)) if !g.is_occupied(c, r) => Ok(()),
            _ => Err(bi_am_rrt::error::InputError::NoRoom),
        }
    }

    /// The nearest position to `p` (on a grid of a tenth of a cell, within 64 cells) where
    /// `map` accepts a start or a goal.
    fn nearest_room<const K: usize>(&self, map: &bi_am_rrt::Map<'_, K>, p: Point) -> Option<Point> {
        let step = 0.1 * f32::from_bits(self.map.cell_bits);
        let mut best: Option<Point> = None;
        for ring in 1..=640i32 {
            if best.is_some_and(|b| b.dist(p) <= ring as f32 * step) {
                break;
            }
            for i in -ring..=ring {
                for (dx, dy) in [(i, -ring), (i, ring), (-ring, i), (ring, i)] {
                    let q = Point::new(p.x + dx as f32 * step, p.y + dy as f32 * step);
                    if self.room(map, q).is_ok() && best.is_none_or(|b| q.dist(p) < b.dist(p)) {
                        best = Some(q);
                    }
                }
            }
        }
        best
    }

    /// This scenario for a robot of `radius` metres: the map inflated for its disc (kept in
    /// [`Scenario::space`]), then checked ([`Scenario::validate`]: the start and goals need
    /// room for the disc, and each leg a way it fits through).
    pub fn with_robot_radius(self, radius: f32) -> Result<Self> {
        self.with_body(radius, false)
    }

    /// [`Scenario::with_robot_radius`], and with `snap` a start or goal where the disc has no
    /// room is moved to the nearest position where it has (within 64 cells), with a line on
    /// standard error that says how far.
    pub fn with_body(mut self, radius: f32, snap: bool) -> Result<Self> {
        if !(radius.is_finite() && radius >= 0.0) {
            bail!(
                "scenario {}: robot radius {radius} (must be a finite number of metres, not negative)",
                self.name
            );
        }
        self.robot_radius = radius;
        self.space = None;
        self.reach = None;
        if radius > 0.0 {
            let g = self.map.grid();
            let mut bits = vec![0u8; OccupancyGrid::bytes_needed(g.cols(), g.rows())];
            bi_am_rrt::map::inflate(&g, radius, &mut bits).map_err(|e| {
                anyhow::anyhow!("scenario {}: robot radius {radius} m: {e}", self.name)
            })?;
            self.space = Some(OwnedGrid {
                bits,
                ..self.map.clone()
            });
            // Where the disc has room, cell by cell (`Live::is_occupied` with the body).
            let map = self.planner_map::<0>()?;
            let live = map.live();
            let reach = OwnedGrid::from_fn(g.cols(), g.rows(), g.cell_size(), |c, r| {
                live.is_occupied(c, r)
            })?;
            drop(map);
            self.reach = Some(reach);
        }
        if snap && radius > 0.0 {
            let map = self.planner_map::<0>()?;
            let mut moved = Vec::new();
            let mut fix = |what: String, p: &mut Point| {
                if self.room(&map, *p) == Err(bi_am_rrt::error::InputError::NoRoom)
                    && let Some(q) = self.nearest_room(&map, *p)
                {
                    moved.push((what, *p, q));
                    *p = q;
                }
            };
            let (mut start, mut goals) = (self.start, self.goals.clone());
            fix("start".into(), &mut start);
            for (i, g) in goals.iter_mut().enumerate() {
                fix(format!("goal {}", i + 1), g);
            }
            for (what, p, q) in moved {
                eprintln!(
                    "scenario {}: {what} moved {:.3} m from {} to {} (room for a robot of radius {radius} m)",
                    self.name,
                    p.dist(q),
                    self.show(p),
                    self.show(q)
                );
            }
            drop(map);
            self.start = start;
            self.goals = goals;
        }
        self.validate()?;
        // A clearance field is built for the radius: rebuilt for the new one.
        match self.clearance.take() {
            Some(c) => self.with_clearance(c.margin, c.weight),
            None => Ok(self),
        }
    }

    /// Where the robot's disc can go, to within a cell ([`Scenario::reach`]), or the map.
    pub fn reach_map(&self) -> &OwnedGrid {
        self.reach.as_ref().unwrap_or(&self.map)
    }

    /// The cell (column, row) of the start: the component a diffusion table baked for this
    /// scenario covers (`TableOptions::keep`).
    pub fn start_cell(&self) -> Option<(u16, u16)> {
        self.reach_grid().cell_of(self.start)
    }

    /// [`Scenario::reach_map`]'s core view.
    pub fn reach_grid(&self) -> OccupancyGrid<'_> {
        self.reach_map().grid()
    }

    /// The hash a diffusion table baked for this scenario's robot records
    /// ([`bi_am_rrt::metric::map_hash`] of the map and the radius); `None` for a point (the
    /// bake hashes the grid it is given).
    pub fn table_hash(&self) -> Option<u32> {
        if self.robot_radius <= 0.0 {
            return None;
        }
        let g = self.map.grid().inflated_for(self.robot_radius).ok()?;
        bi_am_rrt::metric::map_hash(&g)
    }

    /// The core's map of this scenario for its robot (with a body: the inflated grid, baked).
    pub fn planner_map<const K: usize>(&self) -> Result<bi_am_rrt::Map<'_, K>> {
        let map = self.with_clearance_field(bi_am_rrt::Map::new(self.map.grid()))?;
        let Some(space) = &self.space else {
            return Ok(map);
        };
        let space = space
            .grid()
            .inflated_for(self.robot_radius)
            .map_err(|e| anyhow::anyhow!("scenario {}: {e}", self.name))?;
        map.with_baked_body(space)
            .map_err(|e| anyhow::anyhow!("scenario {}: {e}", self.name))
    }
}

impl Scenario {
    /// This scenario with a clearance preference: paths keep `margin` metres beyond the
    /// robot's body where the space allows, a metre at the body's edge costing `1 + weight`
    /// ([`bi_am_rrt::clearance`]). Set the robot's radius first (the field is built for it).
    /// A margin of 0 or a weight of 0 removes the preference.
    pub fn with_clearance(mut self, margin: f32, weight: f32) -> Result<Self> {
        if !(weight.is_finite() && weight >= 0.0) {
            bail!(
                "scenario {}: clearance weight {weight} (must be a finite number, not negative)",
                self.name
            );
        }
        self.clearance = None;
        if margin == 0.0 || weight == 0.0 {
            return Ok(self);
        }
        let g = self.map.grid();
        let mut field = vec![0u8; usize::from(g.cols()) * usize::from(g.rows())];
        bi_am_rrt::clearance::clearance_field(&g, self.robot_radius, margin, &mut field).map_err(
            |e| anyhow::anyhow!("scenario {}: clearance margin {margin} m: {e}", self.name),
        )?;
        self.clearance = Some(Clearance {
            margin,
            weight,
            field,
        });
        Ok(self)
    }

    /// `map` with the scenario's clearance field, when it has one.
    pub fn with_clearance_field<'a, const K: usize>(
        &'a self,
        map: bi_am_rrt::Map<'a, K>,
    ) -> Result<bi_am_rrt::Map<'a, K>> {
        match &self.clearance {
            Some(c) => map
                .with_clearance(&c.field)
                .map_err(|e| anyhow::anyhow!("scenario {}: {e}", self.name)),
            None => Ok(map),
        }
    }

    /// The weight the planner's configuration gets (0 without a preference).
    pub fn clearance_weight(&self) -> f32 {
        self.clearance.as_ref().map_or(0.0, |c| c.weight)
    }
}

/// Row-major index of a cell.
fn cell_at(g: &OccupancyGrid<'_>, c: u16, r: u16) -> usize {
    usize::from(r) * usize::from(g.cols()) + usize::from(c)
}

/// Every built-in scenario (small and paper-sized), or the named ones in that order.
fn builtin_set(only: Option<&[String]>) -> Result<Vec<Scenario>> {
    match only {
        None => Ok(builtin::every().map(builtin_scenario).collect()),
        Some(names) => names.iter().map(|n| builtin_by_name(n)).collect(),
    }
}

/// The core's small built-in scenarios as host scenarios.
pub fn builtin_scenarios() -> Vec<Scenario> {
    builtin::ALL.iter().map(|s| builtin_scenario(s)).collect()
}

/// One built-in scenario.
pub fn builtin_scenario(s: &builtin::Scenario) -> Scenario {
    Scenario::new(
        s.name,
        OwnedGrid::from_grid(&s.grid),
        format!("builtin:{}", s.name),
        s.start,
        s.goals.to_vec(),
        Some(s.sigma),
    )
}

/// The built-in scenario of this name.
pub fn builtin_by_name(name: &str) -> Result<Scenario> {
    builtin::by_name(name)
        .map(builtin_scenario)
        .with_context(|| {
            let names: Vec<_> = builtin::every().map(|s| s.name).collect();
            format!("no built-in scenario {name:?} (have {names:?})")
        })
}

#[cfg(test)]
mod tests {
    /// Issue 23: on a ROS map, `start = [50.0, 80.0]` was reported as `(50, 20)`, a position
    /// of the planner's internal frame; errors now speak in the frame the file was written in.
    #[test]
    fn regression_errors_give_positions_in_the_map_frame_the_user_wrote() {
        // 20 m x 10 m at 0.05 m, origin (-5, 2): the frame spans x -5..15, y 2..12.
        let grid = OwnedGrid::from_fn(400, 200, 0.05, |c, _| c == 200).unwrap();
        let load = |_: &Path| {
            Ok(MapFile {
                grid: grid.clone(),
                ros_origin: Some([-5.0, 2.0]),
            })
        };
        let text = "[s]\nfile = \"m.yaml\"\nstart = [50.0, 80.0]\ngoals = [[1.0, 3.0]]\n";
        let e = format!("{:#}", scenarios_from_str(text, load, None).unwrap_err());
        assert!(e.contains("start (50, 80)"), "{e}");
        // Inside the map, on the wall at x = 5 (column 200).
        let text = "[s]\nfile = \"m.yaml\"\nstart = [0.0, 5.0]\ngoals = [[5.01, 7.5]]\n";
        let e = format!("{:#}", scenarios_from_str(text, load, None).unwrap_err());
        assert!(e.contains("goal 1 (5.01, 7.5)"), "{e}");
        // A valid one: positions convert both ways, and `sigma` follows the map (20 m: a
        // fifth of the paper's 30 m) when the file does not give it.
        let text = "[s]\nfile = \"m.yaml\"\nstart = [0.0, 5.0]\ngoals = [[12.5, 11.0]]\n";
        let sc = scenarios_from_str(text, load, None).unwrap().remove(0);
        let [x, y] = sc.user_frame(sc.goals[0]);
        assert!(
            (x - 12.5).abs() < 1e-4 && (y - 11.0).abs() < 1e-4,
            "{x} {y}"
        );
        assert_eq!(sc.sigma_m, None);
        assert!((sc.sigma() - 6.0).abs() < 1e-5, "{}", sc.sigma());
    }

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

    /// `--scenarios builtin` holds the paper-sized maps (100 m, 100 m, 200 m squares), and every
    /// leg of them has a path: the exact optimum is finite and at least the straight line.
    #[test]
    fn builtin_set_has_the_papers_sizes_and_every_leg_has_a_path() {
        let all = load_scenarios(Path::new(BUILTIN_SET), None).unwrap();
        assert_eq!(all.len(), builtin::ALL.len() + builtin::PAPER_SIZED.len());
        let only = ["office_200".to_string(), "trap_100".to_string()];
        let picked = load_scenarios(Path::new(BUILTIN_SET), Some(&only)).unwrap();
        assert_eq!(picked.len(), 2);
        assert_eq!(picked[0].name, "office_200");
        assert!(load_scenarios(Path::new(BUILTIN_SET), Some(&["nope".into()])).is_err());
        for (name, side) in [
            ("trap_100", 100.0),
            ("maze_100", 100.0),
            ("office_200", 200.0),
        ] {
            let s = builtin_by_name(name).unwrap();
            let g = s.map.grid();
            assert_eq!(f32::from(g.cols()) * g.cell_size(), side, "{name}");
            assert_eq!(f32::from(g.rows()) * g.cell_size(), side, "{name}");
            assert!(s.goals.len() >= 5, "{name}");
            let starts = crate::metric::optimum::leg_starts(&s);
            for (k, opt) in crate::metric::optimum::leg_optima(&s)
                .into_iter()
                .enumerate()
            {
                let opt = opt.unwrap_or_else(|| panic!("{name} leg {} unreachable", k + 1));
                let straight = f64::from(starts[k].dist(s.goals[k]));
                assert!(opt >= straight - 1e-3, "{name} leg {}", k + 1);
            }
        }
    }
}
