//! The `bake` command: a map in, a metric table file out.
//!
//! - `diffusion`: the diffusion map ([`crate::metric::diffusion`]) written in the core's table format
//!   (`bi_am_rrt::metric`), readable by `DiffusionTable::new` from a loaded file or an
//!   `include_bytes!` in firmware; optionally also as Rust source with a `static` table.
//! - `geodesic`: the grid graph in a small binary file (magic `BIAMGRPH`), from which the host's
//!   geodesic metric computes exact distances ([`crate::metric::Geodesic`]).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use bi_am_rrt::Point;
use bi_am_rrt::metric::fnv1a32;

use crate::metric::diffusion::aggregate::{self, Aggregation, CellEdges, Coarse};
use crate::metric::diffusion::{self, BasisChoice, DiffusionMap, Options, TableOptions};
use crate::metric::graph::GridGraph;
use crate::scenario::{OwnedGrid, Scenario};

/// What a diffusion map was computed on.
pub enum Basis {
    /// The cell graph: one node per free cell (maps of at most 65,536 free cells).
    Cells(GridGraph),
    /// The table's pieces ([`crate::metric::diffusion::aggregate`]): one node per table entry.
    Pieces {
        /// The cell graph's edges.
        edges: CellEdges,
        /// The pieces.
        agg: Aggregation,
        /// The piece graph.
        coarse: Coarse,
    },
}

/// A baked diffusion table with its figures.
pub struct Baked {
    /// What the map was computed on.
    pub basis: Basis,
    /// The diffusion map (full precision, one point per node of the basis).
    pub map: DiffusionMap,
    /// The table bytes.
    pub table: Vec<u8>,
}

impl Baked {
    /// The cell graph, for bakes computed on it.
    pub fn graph(&self) -> Option<&GridGraph> {
        match &self.basis {
            Basis::Cells(g) => Some(g),
            Basis::Pieces { .. } => None,
        }
    }
}

/// Most free cells the diffusion map is computed on cell by cell; larger maps are computed on
/// their table's pieces (at most as many: a table holds at most 65,536 entries).
pub const CELL_BASIS_MAX: usize = bi_am_rrt::metric::PIECES_MAX_ENTRIES as usize;

/// What a bake of `grid` will hold in memory at most, in bytes (an estimate, measured against
/// the process's peak on the nav2 maps and a 3000 x 3000 map: within a factor of 1.5 above).
pub fn bake_memory(grid: &OwnedGrid, free: usize, on_cells: bool) -> usize {
    let cells = grid.width as usize * grid.height as usize;
    if on_cells {
        // Cell graph (20 edges of 12 bytes), rows of A2 (twice), factor and Lanczos basis.
        free * (20 * 12 + 2 * 21 * 16 + 60 * 16 + 60 * 8) + cells * 8
    } else {
        cells * CellEdges::BYTES_PER_CELL + CELL_BASIS_MAX * (2 * 40 * 16 + 60 * 16 + 60 * 8)
    }
}

/// Builds the diffusion map of `grid` and writes its table: on the cell graph when the map
/// has at most [`CELL_BASIS_MAX`] free cells, otherwise on the pieces of the table
/// ([`crate::metric::diffusion::aggregate`]). Refuses, naming the knob, a bake whose estimated memory exceeds
/// `table.max_memory` or whose table cannot fit `max_bytes`. Shows a progress bar on a
/// terminal.
pub fn bake_diffusion(grid: &OwnedGrid, opts: &Options, table: &TableOptions) -> Result<Baked> {
    let g = grid.grid();
    let cells = grid.width as usize * grid.height as usize;
    let free = (0..grid.height)
        .map(|r| (0..grid.width).filter(|&c| !g.is_occupied(c, r)).count())
        .sum::<usize>();
    let on_cells = match table.basis {
        BasisChoice::Auto => free <= CELL_BASIS_MAX,
        BasisChoice::Cells => true,
        BasisChoice::Pieces => false,
    };
    let need = bake_memory(grid, free, on_cells);
    if need > table.max_memory {
        bail!(
            "the bake of this {} x {} map ({free} free cells) needs about {} MiB, over the {} MiB \
             allowed: raise --max-memory, or bake a coarser copy of the map",
            grid.width,
            grid.height,
            need >> 20,
            table.max_memory >> 20
        );
    }
    // The table records the grid it was baked from.
    let n = bi_am_rrt::map::OccupancyGrid::bytes_needed(grid.width, grid.height);
    // (A hash given by the caller, a robot body's, is kept: `Scenario::table_hash`.)
    let table = &TableOptions {
        map_hash: match table.map_hash {
            Some(h) => Some(h),
            None => Some(fnv1a32(
                grid.bits.get(..n).context("grid shorter than its size")?,
            )),
        },
        ..*table
    };
    let bar = indicatif::ProgressBar::new(4).with_style(
        indicatif::ProgressStyle::with_template("bake [{elapsed}] {bar:20} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let t0 = Instant::now();
    let baked = if on_cells {
        bar.set_message("cell graph");
        let graph = GridGraph::build_keeping(&g, table.keep);
        let graph_s = t0.elapsed().as_secs_f64();
        bar.inc(1);
        bar.set_message(format!("diffusion map of {} cells", graph.len()));
        let mut map = diffusion::diffusion_map(&graph, opts)?;
        map.report.seconds_graph = graph_s;
        bar.inc(2);
        bar.set_message("table");
        let table = diffusion::table_bytes(&graph, &map, table)?;
        Baked {
            basis: Basis::Cells(graph),
            map,
            table,
        }
    } else {
        bar.set_message(format!("cell edges of {cells} cells"));
        let edges = CellEdges::build_keeping(&g, table.keep);
        bar.inc(1);
        bar.set_message("pieces");
        let (fitted, agg) = table.fitted_aggregation(&edges, opts.eigenpairs - 1)?;
        if fitted.max_bytes != table.max_bytes {
            bar.suspend(|| {
                eprintln!(
                    "note: the pieces of this {} x {} map need more than the {}-byte default \
                     table: budget raised to {} bytes (give --max-bytes to fix it)",
                    grid.width,
                    grid.height,
                    table.budget(cells),
                    fitted.max_bytes
                )
            });
        }
        let table = &fitted;
        let graph_s = t0.elapsed().as_secs_f64();
        bar.inc(1);
        bar.set_message(format!(
            "diffusion map of {} pieces ({} x {} cells)",
            agg.count, agg.block, agg.block
        ));
        let (coarse, mut map) = aggregate::aggregated_map(&edges, &agg, opts)?;
        map.report.seconds_graph = graph_s;
        bar.inc(1);
        bar.set_message("table");
        let table = diffusion::aggregated_table_bytes(&edges, &agg, &map, table)?;
        Baked {
            basis: Basis::Pieces { edges, agg, coarse },
            map,
            table,
        }
    };
    bar.finish_and_clear();
    Ok(baked)
}

/// Rust source declaring `pub static NAME: [u8; LEN]` with the table bytes, with a
/// "generated by" header.
pub fn rust_source(name: &str, bytes: &[u8], origin: &str) -> String {
    format!(
        "// @generated by `host-sim bake` from {origin}. Do not edit.\n{}",
        static_array(name, bytes)
    )
}

/// `pub static NAME: [u8; LEN] = [...];` with a comment giving its size and checksum.
fn static_array(name: &str, bytes: &[u8]) -> String {
    let mut s = format!(
        "/// {} bytes, FNV-1a {:08x}.\npub static {name}: [u8; {}] = [\n",
        bytes.len(),
        fnv1a32(bytes),
        bytes.len()
    );
    for chunk in bytes.chunks(16) {
        s.push_str("   ");
        for b in chunk {
            s.push_str(&format!(" 0x{b:02x},"));
        }
        s.push('\n');
    }
    s.push_str("];\n");
    s
}

/// Magic of a geodesic graph file.
pub const GRAPH_MAGIC: [u8; 8] = *b"BIAMGRPH";

/// Serialises a grid graph: magic, version 1, cols, rows (u32), cell (f32), node count, then
/// each node's cell index (u32) and its CSR offsets and targets (u32); weights are implied by
/// the cell offsets. All little-endian, then an FNV-1a of everything before it.
pub fn graph_bytes(g: &GridGraph) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&GRAPH_MAGIC);
    for v in [1u32, g.cols, g.rows] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&g.cell.to_le_bytes());
    out.extend_from_slice(&(g.len() as u32).to_le_bytes());
    out.extend_from_slice(&(g.targets.len() as u32).to_le_bytes());
    for v in g.cell_of_node.iter().chain(&g.offsets).chain(&g.targets) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let sum = fnv1a32(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Reads a graph written by [`graph_bytes`].
pub fn graph_from_bytes(b: &[u8]) -> Result<GridGraph> {
    if b.len() < 36 || b[..8] != GRAPH_MAGIC {
        bail!("not a geodesic graph file");
    }
    let (body, sum) = b.split_at(b.len() - 4);
    if fnv1a32(body) != u32::from_le_bytes(sum.try_into()?) {
        bail!("graph file checksum mismatch");
    }
    let u = |i: usize| -> Result<u32> {
        Ok(u32::from_le_bytes(
            body.get(8 + 4 * i..12 + 4 * i)
                .context("truncated graph file")?
                .try_into()?,
        ))
    };
    if u(0)? != 1 {
        bail!("unsupported graph file version");
    }
    let (cols, rows, cell, n, m) = (
        u(1)?,
        u(2)?,
        f32::from_bits(u(3)?),
        u(4)? as usize,
        u(5)? as usize,
    );
    let words =
        |start: usize, len: usize| -> Result<Vec<u32>> { (start..start + len).map(u).collect() };
    let cell_of_node = words(6, n)?;
    let offsets = words(6 + n, n + 1)?;
    let targets = words(7 + 2 * n, m)?;
    let mut node_of_cell = vec![u32::MAX; (cols * rows) as usize];
    for (i, &c) in cell_of_node.iter().enumerate() {
        *node_of_cell.get_mut(c as usize).context("bad cell index")? = i as u32;
    }
    let mut weights = Vec::with_capacity(m);
    for i in 0..n {
        let (a, bnd) = (offsets[i] as usize, offsets[i + 1] as usize);
        let ci = cell_of_node[i];
        for &t in targets.get(a..bnd).context("bad offsets")? {
            let ct = *cell_of_node.get(t as usize).context("bad target")?;
            let dx = (ct % cols) as f64 - (ci % cols) as f64;
            let dy = (ct / cols) as f64 - (ci / cols) as f64;
            weights.push((dx * dx + dy * dy).sqrt());
        }
    }
    Ok(GridGraph {
        cols,
        rows,
        cell,
        node_of_cell,
        cell_of_node,
        offsets,
        targets,
        weights,
    })
}

/// Writes `bytes` to `path`, creating parent directories.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// How far the table's distances are from the full-precision diffusion distances.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct TableError {
    /// Node pairs compared.
    pub pairs: usize,
    /// Largest absolute difference.
    pub max_abs: f64,
    /// Largest difference relative to the full-precision distance (pairs at distance > 1).
    pub max_rel: f64,
    /// The a-priori bound of an `i16` table: `sqrt(dims) * scale` (0 for `f32`).
    pub bound: f64,
    /// Largest full-precision distance seen (for scale).
    pub max_distance: f64,
    /// 99th percentile of the absolute difference.
    pub p99_abs: f64,
    /// Fraction of pairs whose difference exceeds `bound` (coarse tables trade exactness near
    /// walls for size).
    pub over_bound: f64,
}

/// Compares the baked table with the full-precision map on `pairs` seeded random node pairs.
pub fn table_error(b: &Baked, pairs: usize, seed: u64) -> Result<TableError> {
    use bi_am_rrt::Metric;
    use rand_core::{Rng, SeedableRng};
    let t = bi_am_rrt::DiffusionTable::new(&b.table).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(seed);
    // A random node of the basis and a position it stands for (a cell centre).
    let mut node = || -> Option<(u32, Point)> {
        match &b.basis {
            Basis::Cells(g) => {
                let i = (rng.next_u64() % g.len() as u64) as u32;
                Some((i, g.position(i)))
            }
            Basis::Pieces { edges, agg, .. } => {
                let cells = edges.cols as u64 * edges.rows as u64;
                (0..10_000).find_map(|_| {
                    let cell = (rng.next_u64() % cells) as usize;
                    let p = agg.of_cell(cell)?;
                    let (c, r) = (cell as u32 % edges.cols, cell as u32 / edges.cols);
                    let at = |i: u32| (i as f32 + 0.5) * edges.cell;
                    Some((p, Point::new(at(c), at(r))))
                })
            }
        }
    };
    let (mut max_abs, mut max_rel, mut max_d) = (0.0f64, 0.0f64, 0.0f64);
    let mut errs = Vec::with_capacity(pairs);
    for _ in 0..pairs {
        let (Some((i, pi)), Some((j, pj))) = (node(), node()) else {
            bail!("no free cell found to measure the table on");
        };
        let exact = b.map.distance(i, j);
        let got = t.distance(pi, pj) as f64;
        let err = (got - exact).abs();
        errs.push(err);
        max_abs = max_abs.max(err);
        if exact > 1.0 {
            max_rel = max_rel.max(err / exact);
        }
        max_d = max_d.max(exact);
    }
    let h = t.header();
    let bound = match h.kind {
        bi_am_rrt::metric::ElementKind::I16 => (h.dims as f64).sqrt() * h.scale as f64,
        bi_am_rrt::metric::ElementKind::F32 => 0.0,
    };
    let over = errs.iter().filter(|&&e| e > bound).count() as f64 / pairs.max(1) as f64;
    errs.sort_by(f64::total_cmp);
    let p99_abs = errs.get(errs.len() * 99 / 100).copied().unwrap_or(0.0);
    Ok(TableError {
        pairs,
        max_abs,
        max_rel,
        bound,
        max_distance: max_d,
        p99_abs,
        over_bound: over,
    })
}

/// The cost of the geodesic metric on a graph: seconds per distance field (median of
/// `samples` Dijkstra runs), and with `all`, seconds to compute every field (all-pairs
/// distances, on all cores, nothing kept) for comparison with a precomputed matrix.
pub fn geodesic_costs(g: &GridGraph, samples: usize, all: bool) -> (f64, Option<f64>) {
    use rayon::prelude::*;
    let n = g.len() as u32;
    let mut times = Vec::new();
    let mut dist = Vec::new();
    for k in 0..samples as u32 {
        let t0 = Instant::now();
        g.dijkstra((k * 7919) % n.max(1), &mut dist);
        times.push(t0.elapsed().as_secs_f64());
    }
    let per_field = crate::results::stats::median(&mut times).unwrap_or(0.0);
    let total = all.then(|| {
        let t0 = Instant::now();
        (0..n)
            .into_par_iter()
            .for_each_init(Vec::new, |d, s| g.dijkstra(s, d));
        t0.elapsed().as_secs_f64()
    });
    (per_field, total)
}

/// What `export` wrote for a firmware.
pub struct Exported {
    /// The Rust source file (`include!` it).
    pub source: std::path::PathBuf,
    /// Bytes of the packed grid.
    pub grid_bytes: usize,
    /// Bytes of the diffusion table.
    pub table_bytes: usize,
    /// How far the table is from full precision.
    pub error: TableError,
    /// Bytes of the roadmap (0 when the map has none: more corners than
    /// [`crate::metric::roadmap::MAX_NODES`]).
    pub roadmap_bytes: usize,
    /// Why the map has no roadmap, when it has none.
    pub no_roadmap: Option<String>,
}

/// Writes a scenario for a firmware into `dir`: `NAME.grid` (the bit-packed grid of
/// `bi_am_rrt::map`), `NAME.table` (its diffusion table, `table` options), `NAME.roadmap` (its
/// roadmap, [`crate::metric::roadmap::of_scenario`]; empty when it has none) and `NAME.rs`, Rust
/// source that a firmware `include!`s: grid, table and roadmap as `static` byte arrays (flash), the
/// grid's shape, the start, the goals and `sigma`, and the firmware's mission ([`Mission`]).
pub fn export_flash(
    sc: &crate::scenario::Scenario,
    table: &TableOptions,
    dir: &Path,
    mission: &Mission,
) -> Result<Exported> {
    // With a robot body the table is baked on where its disc can go (the cells with room), and
    // the grid inflated by the cells rule, the planner's fast test, goes to flash beside the
    // map's own (`SPACE`, `ROBOT_RADIUS`).
    let table = &TableOptions {
        map_hash: sc.table_hash(),
        keep: sc.start_cell(),
        ..*table
    };
    let baked = bake_diffusion(sc.reach_map(), &Options::default(), table)?;
    let error = table_error(&baked, 20_000, 1)?;
    let name = &sc.name;
    let space: &[u8] = sc.space.as_ref().map_or(&[], |s| &s.bits);
    write_file(&dir.join(format!("{name}.grid")), &sc.map.bits)?;
    if !space.is_empty() {
        write_file(&dir.join(format!("{name}.space")), space)?;
    }
    write_file(&dir.join(format!("{name}.table")), &baked.table)?;
    // The roadmap of the first solution (core feature `roadmap`): baked on the grid the
    // planner tests paths on, for the planner's map, as the simulator bakes it.
    let (roadmap, no_roadmap) = match crate::metric::roadmap::of_scenario(sc) {
        Ok(r) => (r.bytes, None),
        Err(e) => (Vec::new(), Some(format!("{e:#}"))),
    };
    write_file(&dir.join(format!("{name}.roadmap")), &roadmap)?;
    let pt = |p: bi_am_rrt::Point| format!("({:?}, {:?})", p.x, p.y);
    let goals: Vec<String> = sc.goals.iter().map(|&g| pt(g)).collect();
    let src = format!(
        "// @generated by `host-sim export` from {}. Do not edit.\n\
         /// Scenario name.\npub const NAME: &str = {:?};\n\
         /// Grid columns.\npub const COLS: u16 = {};\n\
         /// Grid rows.\npub const ROWS: u16 = {};\n\
         /// Cell side in metres.\npub const CELL: f32 = {:?};\n\
         /// Start position (x, y) in metres.\npub const START: (f32, f32) = {};\n\
         /// Goals in order.\npub const GOALS: [(f32, f32); {}] = [{}];\n\
         /// Connection distance of the two trees (m).\npub const SIGMA: f32 = {:?};\n\
         /// The robot's radius (m; 0: a point).\npub const ROBOT_RADIUS: f32 = {:?};\n\
         /// The occupancy grid, bit-packed as `bi_am_rrt::map::pack_grid` does.\n{}\
         /// The grid inflated for the robot's disc (`bi_am_rrt::map::inflate`; empty for a point).\n{}\
         /// The diffusion table (`bi_am_rrt::DiffusionTable::new`); max error {:.3e} over {} pairs, \
         largest distance {:.3e}.\n{}\
         /// The roadmap (`bi_am_rrt::roadmap::Roadmap::from_bytes`, core feature `roadmap`; \
         empty when the map has none).\n#[allow(dead_code)]\n{}\
         /// The mission (`host-sim export --planners`): the tuned Bi-AM-RRT*(D), or the paper's.\n\
         #[allow(dead_code)]\npub const TUNED: bool = {};\n\
         /// The mission (`--all-goals`): every goal in turn, or goal 1.\n\
         #[allow(dead_code)]\npub const ALL_GOALS: bool = {};\n\
         /// The mission (`--walkers`): people pacing across goal 1's way (0-4).\n\
         #[allow(dead_code)]\npub const WALKERS: usize = {};\n\
         /// The mission (`--door`): a door closing and opening across goal 1's line.\n\
         #[allow(dead_code)]\npub const DOOR: bool = {};\n",
        sc.source,
        name,
        sc.map.width,
        sc.map.height,
        f32::from_bits(sc.map.cell_bits),
        pt(sc.start),
        goals.len(),
        goals.join(", "),
        sc.sigma(),
        sc.robot_radius,
        static_array("GRID", &sc.map.bits),
        static_array("SPACE", space),
        error.max_abs,
        error.pairs,
        error.max_distance,
        static_array("TABLE", &baked.table),
        static_array("ROADMAP", &roadmap),
        mission.tuned,
        mission.all_goals,
        mission.walkers,
        mission.door,
    );
    let source = dir.join(format!("{name}.rs"));
    write_file(&source, src.as_bytes())?;
    // The firmware example includes `scenario.rs`: the last scenario exported to `dir`.
    write_file(&dir.join("scenario.rs"), src.as_bytes())?;
    Ok(Exported {
        source,
        grid_bytes: sc.map.bits.len() + space.len(),
        table_bytes: baked.table.len(),
        error,
        roadmap_bytes: roadmap.len(),
        no_roadmap,
    })
}

/// The loud warning `bake` and `export` print when a table's largest error exceeds 2 % of the
/// largest distance (the planner then steers by a distorted metric), `None` when it does not.
pub fn error_warning(e: &TableError) -> Option<String> {
    let share = e.max_abs / e.max_distance.max(f64::MIN_POSITIVE);
    (share > 0.02).then(|| {
        format!(
            "WARNING: the table's largest error is {:.1} % of the largest distance (over 2 %): \
             the planner will steer by a distorted metric. Give it more bytes (--max-bytes), \
             a smaller --coarsen, or --layout pieces.",
            100.0 * share
        )
    })
}

/// `host-sim bake --metric diffusion`: bakes `grid` (called `name` in messages), writes the
/// table to `out` (and Rust source to `rust`), and prints the figures of the bake and of the
/// table's error against full precision.
pub fn diffusion_command(
    grid: &OwnedGrid,
    name: &str,
    out: &Path,
    table: &TableOptions,
    rust: Option<&Path>,
) -> Result<()> {
    let t0 = Instant::now();
    let baked = bake_diffusion(grid, &Options::default(), table)?;
    let secs = t0.elapsed().as_secs_f64();
    write_file(out, &baked.table)?;
    let r = &baked.map.report;
    println!(
        "{name}: {} nodes, {} non-zeros; graph {:.3} s, matrix {:.3} s, factor {:.3} s, \
         Lanczos {:.3} s ({} solves, {} restarts), t {:.3} s; total {secs:.3} s",
        r.nodes,
        r.nonzeros,
        r.seconds_graph,
        r.seconds_matrix,
        r.seconds_factor,
        r.seconds_lanczos,
        r.solves,
        r.restarts,
        r.seconds_t
    );
    println!("eigenvalues: {:?}", r.eigenvalues);
    println!(
        "max relative residual {:.2e}, orthogonality {:.2e}, t = {:.1}, Pearson(d_D, d_G) = {:.4}",
        r.residuals.iter().fold(0.0f64, |a, &b| a.max(b)),
        r.orthogonality,
        r.t,
        r.pearson
    );
    println!("table: {} bytes -> {}", baked.table.len(), out.display());
    let e = table_error(&baked, 20_000, 1)?;
    let against = match &baked.basis {
        Basis::Cells(_) => "full precision over cell".to_string(),
        Basis::Pieces { agg, .. } => format!(
            "the map of its {} pieces ({} x {} blocks; the map is computed on them, so this is \
             the quantisation) over free-cell",
            agg.count, agg.block, agg.block
        ),
    };
    println!(
        "table vs {against} pairs ({}): max error {:.3e} (relative {:.3e}), 99th percentile {:.3e}, \
         {:.2} % of pairs above the quantisation bound {:.3e}; largest distance {:.3e}",
        e.pairs,
        e.max_abs,
        e.max_rel,
        e.p99_abs,
        100.0 * e.over_bound,
        e.bound,
        e.max_distance
    );
    println!(
        "largest error = {:.2} % of the largest distance",
        100.0 * e.max_abs / e.max_distance.max(f64::MIN_POSITIVE)
    );
    if let Some(w) = error_warning(&e) {
        eprintln!("{w}");
    }
    if let Some(rs) = rust {
        let src = rust_source("DIFFUSION_TABLE", &baked.table, name);
        write_file(rs, src.as_bytes())?;
    }
    Ok(())
}

/// `host-sim bake --metric geodesic`: writes the grid graph of `grid` to `out` and prints the
/// cost of one distance field (and of all of them with `all_pairs`).
pub fn geodesic_command(grid: &OwnedGrid, name: &str, out: &Path, all_pairs: bool) -> Result<()> {
    let t0 = Instant::now();
    let graph = GridGraph::build(&grid.grid());
    let bytes = graph_bytes(&graph);
    let secs = t0.elapsed().as_secs_f64();
    write_file(out, &bytes)?;
    println!(
        "{name}: geodesic graph of {} nodes, {} directed edges in {secs:.3} s; {} bytes -> {}",
        graph.len(),
        graph.edge_count(),
        bytes.len(),
        out.display()
    );
    let (per_field, total) = geodesic_costs(&graph, 25, all_pairs);
    println!(
        "one distance field (Dijkstra): {:.3} ms (median of 25)",
        per_field * 1e3
    );
    if let Some(t) = total {
        println!("every field (all-pairs distances, all cores): {t:.2} s");
    }
    Ok(())
}

/// Flash the firmware example leaves to a scenario's grid and table: 144 KiB of the 256 KiB
/// it is held to (the rest is code, about 90 KiB, strings and tables of the twin mission).
pub const FIRMWARE_DATA_BYTES: usize = 144 * 1024;

/// The table budget an export uses: the one asked for, or with `--max-bytes 0` (auto) the
/// bake's own default capped so that grid and table fit `data` bytes of flash. Refuses, naming
/// the way out, when the grid alone leaves no room for a useful table.
pub fn flash_table_options(
    sc: &Scenario,
    table: &TableOptions,
    data: usize,
) -> Result<TableOptions> {
    let grid = sc.map.bits.len();
    let mut t = *table;
    if t.max_bytes != 0 {
        return Ok(t);
    }
    // A table needs at least a few hundred pieces of 10 coordinates, and the piece map.
    let cells = usize::from(sc.map.width) * usize::from(sc.map.height);
    let least = cells / 2 + 16 * 1024;
    let room = data.saturating_sub(grid);
    if room < least {
        anyhow::bail!(
            "{}: does not fit the firmware's flash: the grid alone is {grid} bytes ({} x {} cells \
             at 1 bit) and its table needs at least {least} bytes (half a byte per cell for the \
             piece map), with {data} bytes of flash for data (--flash-data). Down-sample the \
             map (larger cells) or give the firmware more flash.",
            sc.name,
            sc.map.width,
            sc.map.height
        );
    }
    t.max_bytes = t.budget(cells).min(room);
    Ok(t)
}

/// What a firmware flies with the scenario it includes: the options it used to read from
/// build-time environment variables, now written beside the scenario by `host-sim export`
/// (`scenario.rs`'s `TUNED`, `ALL_GOALS`, `WALKERS`, `DOOR`), so a firmware's whole
/// configuration comes from the one command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Mission {
    /// The tuned Bi-AM-RRT*(D) (else the paper's).
    pub tuned: bool,
    /// Every goal in turn (else goal 1).
    pub all_goals: bool,
    /// People pacing across goal 1's way, 0-4.
    pub walkers: u8,
    /// A door closing and opening across goal 1's line.
    pub door: bool,
}

/// `host-sim export`: writes a scenario's flash files ([`export_flash`]) within `flash_data`
/// bytes ([`flash_table_options`]) and prints their sizes and the table's error.
pub fn export_command(
    sc: &Scenario,
    table: &TableOptions,
    out: &Path,
    flash_data: usize,
    mission: &Mission,
) -> Result<()> {
    let t0 = Instant::now();
    let table = &flash_table_options(sc, table, flash_data)?;
    let ex = export_flash(sc, table, out, mission)?;
    let e = &ex.error;
    println!(
        "{}: grid {} bytes, table {} bytes (max error {:.3e} = {:.2} % of the largest distance {:.3e} over {} pairs) in {:.1} s -> {}",
        sc.name,
        ex.grid_bytes,
        ex.table_bytes,
        e.max_abs,
        100.0 * e.max_abs / e.max_distance.max(f64::MIN_POSITIVE),
        e.max_distance,
        e.pairs,
        t0.elapsed().as_secs_f64(),
        ex.source.display()
    );
    if let Some(w) = error_warning(e) {
        eprintln!("{w}");
    }
    match &ex.no_roadmap {
        None => println!(
            "  roadmap {} bytes (flown by a firmware built with the core's `roadmap` feature)",
            ex.roadmap_bytes
        ),
        Some(why) => println!("  no roadmap: {why}"),
    }
    let data = ex.grid_bytes + ex.table_bytes;
    if data > flash_data {
        eprintln!(
            "WARNING: grid and table are {data} bytes, over the {flash_data} bytes of flash the \
             firmware example leaves to data (--flash-data): give --max-bytes at most {}",
            flash_data.saturating_sub(ex.grid_bytes)
        );
    } else {
        println!("  flash data {data} of {flash_data} bytes: fits the firmware example");
    }
    // The roadmap's code in the firmware example (the core's `roadmap` feature): 8,184 bytes
    // of flash measured on the office export (docs/guides/firmware.md), rounded up.
    const ROADMAP_CODE_BYTES: usize = 9 * 1024;
    let with_roadmap = data + ex.roadmap_bytes + ROADMAP_CODE_BYTES;
    if ex.roadmap_bytes > 0 && with_roadmap > flash_data && data <= flash_data {
        println!(
            "  with the roadmap and its code (about {ROADMAP_CODE_BYTES} bytes) {with_roadmap} \
             bytes, over the {flash_data}: a firmware that flies it needs --max-bytes at most {}",
            flash_data.saturating_sub(ex.grid_bytes + ex.roadmap_bytes + ROADMAP_CODE_BYTES)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 23: `export` of a nav2 map fits the firmware's flash or says why not.
    #[test]
    fn export_fits_the_firmware_flash_or_says_why_not() {
        let mut sc = crate::scenario::builtin_by_name("office_200").unwrap();
        let auto = TableOptions::default();
        // The office: its own 128 KiB budget already fits.
        let t = flash_table_options(&sc, &auto, FIRMWARE_DATA_BYTES).unwrap();
        assert_eq!(t.max_bytes, auto.budget(40_000));
        // A larger map: the table gets what the grid leaves.
        sc.map = OwnedGrid::from_fn(600, 300, 0.05, |_, _| false).unwrap();
        let t = flash_table_options(&sc, &auto, FIRMWARE_DATA_BYTES).unwrap();
        assert_eq!(t.max_bytes, FIRMWARE_DATA_BYTES - sc.map.bits.len());
        // A budget given by hand is kept.
        let mut hand = auto;
        hand.max_bytes = 50_000;
        assert_eq!(
            flash_table_options(&sc, &hand, FIRMWARE_DATA_BYTES)
                .unwrap()
                .max_bytes,
            50_000
        );
        // Warehouse-sized: refused, naming the way out.
        sc.map = OwnedGrid::from_fn(1006, 1674, 0.03, |_, _| false).unwrap();
        let e = flash_table_options(&sc, &auto, FIRMWARE_DATA_BYTES).unwrap_err();
        assert!(format!("{e}").contains("Down-sample the map"), "{e}");
    }

    #[test]
    fn graph_file_round_trip() {
        let g = OwnedGrid::from_fn(9, 7, 1.0, |c, r| c == 4 && r > 1).unwrap();
        let graph = GridGraph::build(&g.grid());
        let bytes = graph_bytes(&graph);
        let back = graph_from_bytes(&bytes).unwrap();
        assert_eq!(back.cell_of_node, graph.cell_of_node);
        assert_eq!(back.targets, graph.targets);
        assert_eq!(back.weights, graph.weights);
        let mut bad = bytes.clone();
        bad[20] ^= 1;
        assert!(graph_from_bytes(&bad).is_err());
        assert!(graph_from_bytes(&bytes[..30]).is_err());
    }

    #[test]
    fn rust_source_has_a_header() {
        let s = rust_source("T", &[1, 2, 3], "test");
        assert!(s.starts_with("// @generated by `host-sim bake`"));
        assert!(s.contains("pub static T: [u8; 3]"));
    }
}
