//! The diffusion map of a grid graph (Coifman & Lafon; Chen et al.'s use for motion planning;
//! the AM-RRT* reference's normalisations), baked into the core's table format.
//!
//! 1. Kernel on the edges: `a_ij = exp(-w_ij^2 / (2 r))` (`w` in metres, `r` the cell size);
//!    no diagonal. `D = diag(row sums)`.
//! 2. `A1 = (A + D) / 2`, `A2 = D^-1 A1 D^-1`, `D2 = diag(row sums of A2)`,
//!    `E = D2^-1/2 A2 D2^-1/2` (symmetric, eigenvalues in (-1, 1], the top one exactly 1).
//! 3. The top 11 eigenpairs of `E`. Plain Lanczos on `E` would need thousands of products: the
//!    top eigenvalues are packed against 1 (office: gaps of 3e-6). Instead: a sparse Cholesky
//!    factorisation of `sigma I - E` (faer) with `sigma` slightly above 1, and a thick-restart
//!    Lanczos with full reorthogonalisation on its inverse (shift-invert), where those
//!    eigenvalues become large and well separated; the projected problems are solved by faer's
//!    dense self-adjoint eigensolver. Final eigenvalues are Rayleigh quotients with `E`.
//! 4. The trivial pair (lambda = 1) is dropped and 10 kept; coordinates
//!    `n * D2^-1/2 v_k * lambda_k^t`.
//! 5. The time scale `t` maximises the Pearson correlation between diffusion distance and graph
//!    (Dijkstra) distance over 25 x 25 node pairs drawn with a seeded generator: a log-spaced
//!    scan of `t` in `[1, 10^7]`, refined by golden-section search.

pub mod aggregate;

use std::time::Instant;

use anyhow::{Context, Result, bail};
use bi_am_rrt::metric::{ElementKind, TABLE_HEADER_LEN, TableHeader, write_table};
use faer::prelude::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatMut, Side};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

use crate::metric::diffusion::aggregate::{Aggregation, CellEdges};
use crate::metric::graph::GridGraph;

/// Options of the diffusion bake.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Eigenpairs computed (the top one is dropped).
    pub eigenpairs: usize,
    /// `sigma - 1` of the shift-invert.
    pub shift: f64,
    /// Relative residual at which a Ritz pair of the inverse counts as converged.
    pub tol: f64,
    /// Lanczos basis size.
    pub basis: usize,
    /// Restarts allowed.
    pub max_restarts: usize,
    /// Sources and targets sampled for the choice of `t` (pairs = square of this).
    pub pairs: usize,
    /// Seed of the start vector and of the pair sampling.
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            eigenpairs: 11,
            shift: 1e-4,
            tol: 1e-14,
            basis: 48,
            max_restarts: 60,
            pairs: 25,
            seed: 1,
        }
    }
}

/// Timings and accuracy figures of a bake.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Report {
    /// Nodes of the grid graph.
    pub nodes: usize,
    /// Non-zeros of `E` (diagonal included).
    pub nonzeros: usize,
    /// All eigenvalues computed, descending (the first is the trivial 1).
    pub eigenvalues: Vec<f64>,
    /// `||E v - lambda v|| / |lambda|` of each.
    pub residuals: Vec<f64>,
    /// `max |V^T V - I|`.
    pub orthogonality: f64,
    /// Linear solves (applications of the inverse).
    pub solves: usize,
    /// Lanczos restarts.
    pub restarts: usize,
    /// The time scale chosen.
    pub t: f64,
    /// Pearson correlation of diffusion and graph distances at that `t`.
    pub pearson: f64,
    /// Seconds: graph construction (filled by the caller), matrix, factorisation, Lanczos,
    /// choice of `t`.
    pub seconds_graph: f64,
    /// Seconds building `E`.
    pub seconds_matrix: f64,
    /// Seconds in the Cholesky factorisation.
    pub seconds_factor: f64,
    /// Seconds in Lanczos.
    pub seconds_lanczos: f64,
    /// Seconds choosing `t`.
    pub seconds_t: f64,
}

/// A diffusion map: 10 (or `eigenpairs - 1`) coordinates per graph node.
#[derive(Clone, Debug)]
pub struct DiffusionMap {
    /// Coordinates, node-major: `coords[node * dims + k]`.
    pub coords: Vec<f64>,
    /// Coordinates per node.
    pub dims: usize,
    /// Accuracy and timing figures.
    pub report: Report,
}

impl DiffusionMap {
    /// The coordinates of a node.
    pub fn node(&self, n: u32) -> &[f64] {
        &self.coords[n as usize * self.dims..(n as usize + 1) * self.dims]
    }

    /// Diffusion distance between two nodes.
    pub fn distance(&self, a: u32, b: u32) -> f64 {
        self.node(a)
            .iter()
            .zip(self.node(b))
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    }
}

/// `E` as CSR-like rows (column, value), diagonal included.
struct Sym {
    rows: Vec<Vec<(u32, f64)>>,
}

impl Sym {
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (yi, row) in y.iter_mut().zip(&self.rows) {
            *yi = row.iter().map(|&(j, v)| v * x[j as usize]).sum();
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Computes the diffusion map of `graph` (module docs).
pub fn diffusion_map(graph: &GridGraph, opts: &Options) -> Result<DiffusionMap> {
    let n = graph.len();
    let k = opts.eigenpairs;
    if n <= k + 2 {
        bail!("graph too small for {k} eigenpairs: {n} nodes");
    }
    let mut report = Report {
        nodes: n,
        ..Report::default()
    };
    let t0 = Instant::now();
    // 1-2: the normalised symmetric matrix.
    let r = graph.cell as f64;
    let kernel = |w_cells: f64| {
        let w = w_cells * r;
        (-(w * w) / (2.0 * r)).exp()
    };
    let d: Vec<f64> = (0..n as u32)
        .map(|i| graph.neighbours(i).map(|(_, w)| kernel(w)).sum())
        .collect();
    // A2 = D^-1 (A + D)/2 D^-1: off-diagonal a/(2 d_i d_j), diagonal 1/(2 d_i).
    let rows: Vec<Vec<(u32, f64)>> = (0..n as u32)
        .map(|i| {
            let di = d[i as usize];
            let mut row: Vec<(u32, f64)> = graph
                .neighbours(i)
                .map(|(j, w)| (j, kernel(w) / (2.0 * di * d[j as usize])))
                .collect();
            row.push((i, 1.0 / (2.0 * di)));
            row
        })
        .collect();
    report.seconds_matrix = t0.elapsed().as_secs_f64();
    diffusion_of(rows, n as f64, opts, report, &|src, dist| {
        graph.dijkstra(src, dist)
    })
}

/// Steps 2 (from `D2`) to 5 for any symmetric `A2` given as rows with the diagonal, and
/// coordinates multiplied by `mass` (the number of map cells the nodes stand for): the cell
/// graph's own matrix, or the aggregated one of [`crate::metric::diffusion::aggregate`]. `dijkstra(src, dist)`
/// writes graph distances from `src` (any unit: only their correlation is used).
pub(crate) fn diffusion_of(
    mut rows: Vec<Vec<(u32, f64)>>,
    mass: f64,
    opts: &Options,
    mut report: Report,
    dijkstra: &(dyn Fn(u32, &mut Vec<f64>) + Sync),
) -> Result<DiffusionMap> {
    let n = rows.len();
    let k = opts.eigenpairs;
    if n <= k + 2 {
        bail!("graph too small for {k} eigenpairs: {n} nodes");
    }
    report.nodes = n;
    let t0 = Instant::now();
    let d2: Vec<f64> = rows
        .iter()
        .map(|row| row.iter().map(|&(_, v)| v).sum())
        .collect();
    let s: Vec<f64> = d2.iter().map(|v| 1.0 / v.sqrt()).collect();
    for (i, row) in rows.iter_mut().enumerate() {
        for (j, v) in row.iter_mut() {
            *v *= s[i] * s[*j as usize];
        }
    }
    let e = Sym { rows };
    report.nonzeros = e.rows.iter().map(Vec::len).sum();
    report.seconds_matrix += t0.elapsed().as_secs_f64();

    // 3: shift-invert Lanczos.
    let t1 = Instant::now();
    let sigma = 1.0 + opts.shift;
    let mut triplets = Vec::with_capacity(report.nonzeros);
    for (i, row) in e.rows.iter().enumerate() {
        for &(j, v) in row {
            // Lower triangle only: the factorisation reads one side.
            if (j as usize) <= i {
                let val = if j as usize == i { sigma - v } else { -v };
                triplets.push(Triplet::new(i, j as usize, val));
            }
        }
    }
    let shifted = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| anyhow::anyhow!("building sigma I - E: {e:?}"))?;
    let llt = shifted
        .sp_cholesky(Side::Lower)
        .map_err(|e| anyhow::anyhow!("Cholesky of sigma I - E: {e:?}"))?;
    report.seconds_factor = t1.elapsed().as_secs_f64();

    let t2 = Instant::now();
    let mut solves = 0usize;
    let mut apply = |x: &[f64], y: &mut [f64]| {
        y.copy_from_slice(x);
        llt.solve_in_place(MatMut::from_column_major_slice_mut(y, n, 1));
        solves += 1;
    };
    let (vals, vecs, restarts) = lanczos_top(n, k, opts, &mut apply)?;
    report.solves = solves;
    report.restarts = restarts;
    // Rayleigh quotients with E, residuals, orthogonality.
    let mut ev = vec![0.0; n];
    let mut pairs: Vec<(f64, Vec<f64>)> = Vec::with_capacity(k);
    for v in vecs.into_iter().take(k) {
        e.mul(&v, &mut ev);
        let lambda = dot(&v, &ev) / dot(&v, &v);
        pairs.push((lambda, v));
    }
    let _ = vals;
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (lambda, v) in &pairs {
        e.mul(v, &mut ev);
        let res: Vec<f64> = ev.iter().zip(v).map(|(a, b)| a - lambda * b).collect();
        report
            .residuals
            .push(norm(&res) / lambda.abs().max(f64::MIN_POSITIVE));
        report.eigenvalues.push(*lambda);
    }
    let mut ortho = 0.0f64;
    for i in 0..k {
        for j in 0..=i {
            let target = if i == j { 1.0 } else { 0.0 };
            ortho = ortho.max((dot(&pairs[i].1, &pairs[j].1) - target).abs());
        }
    }
    report.orthogonality = ortho;
    report.seconds_lanczos = t2.elapsed().as_secs_f64();

    // 4-5: coordinates before the time scale, and the choice of t.
    let t3 = Instant::now();
    let dims = k - 1;
    let kept = &pairs[1..];
    let mut base = Vec::with_capacity(n * dims);
    for (i, si) in s.iter().enumerate() {
        base.extend(kept.iter().map(|(_, v)| mass * v[i] * si));
    }
    let lambdas: Vec<f64> = kept.iter().map(|(l, _)| *l).collect();
    let (t, pearson) = choose_t(n, dijkstra, &base, &lambdas, opts);
    report.t = t;
    report.pearson = pearson;
    report.seconds_t = t3.elapsed().as_secs_f64();
    // The lazy walk's eigenvalues are non-negative.
    let scale: Vec<f64> = lambdas.iter().map(|l| l.max(0.0).powf(t)).collect();
    let coords = base
        .chunks(dims)
        .flat_map(|c| c.iter().zip(&scale).map(|(x, s)| x * s))
        .collect();
    Ok(DiffusionMap {
        coords,
        dims,
        report,
    })
}

/// Thick-restart Lanczos with full reorthogonalisation for the `k` largest eigenpairs of the
/// symmetric operator `apply`. Returns Ritz values (descending), vectors and restarts used.
fn lanczos_top(
    n: usize,
    k: usize,
    opts: &Options,
    apply: &mut dyn FnMut(&[f64], &mut [f64]),
) -> Result<(Vec<f64>, Vec<Vec<f64>>, usize)> {
    let m = opts.basis.max(2 * k + 4).min(n);
    let keep = (k + 6).min(m - 2);
    let mut rng = XorShiftRng::seed_from_u64(opts.seed);
    let mut v0: Vec<f64> = (0..n)
        .map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        .collect();
    let nv = norm(&v0);
    v0.iter_mut().for_each(|x| *x /= nv);
    let mut basis: Vec<Vec<f64>> = vec![v0];
    // Projected matrix H (symmetric), grown column by column.
    let mut h = vec![vec![0.0f64; m + 1]; m + 1];
    let mut w = vec![0.0; n];
    for restart in 0..=opts.max_restarts {
        // Expand the basis to m vectors.
        let mut beta = 0.0;
        for j in basis.len() - 1..m {
            apply(&basis[j], &mut w);
            // Two passes of classical Gram-Schmidt against the whole basis.
            let mut col = vec![0.0; basis.len()];
            for _ in 0..2 {
                for (ci, vi) in col.iter_mut().zip(&basis) {
                    let c = dot(vi, &w);
                    *ci += c;
                    w.iter_mut().zip(vi).for_each(|(x, y)| *x -= c * y);
                }
            }
            // Column j of H and, by symmetry, row j.
            for (i, c) in col.into_iter().enumerate() {
                h[i][j] += c;
                h[j][i] = h[i][j];
            }
            beta = norm(&w);
            if j + 1 < m {
                if beta <= 1e-300 {
                    bail!("Lanczos breakdown at step {j}");
                }
                basis.push(w.iter().map(|x| x / beta).collect());
            }
        }
        // Ritz pairs of the projected matrix.
        let hm = Mat::<f64>::from_fn(m, m, |i, j| h[i][j]);
        let eig = hm
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| anyhow::anyhow!("projected eigenproblem: {e:?}"))?;
        let (theta, y) = (eig.S().column_vector(), eig.U());
        // Descending order.
        let order: Vec<usize> = (0..m).rev().collect();
        let converged = order
            .iter()
            .take(k)
            .all(|&c| (beta * y[(m - 1, c)]).abs() <= opts.tol * theta[c].abs());
        let take = if converged { k } else { keep };
        let ritz: Vec<Vec<f64>> = order
            .iter()
            .take(take)
            .map(|&c| {
                let mut u = vec![0.0; n];
                for (i, vi) in basis.iter().enumerate() {
                    let yi = y[(i, c)];
                    u.iter_mut().zip(vi).for_each(|(x, v)| *x += yi * v);
                }
                u
            })
            .collect();
        if converged || restart == opts.max_restarts {
            if !converged {
                bail!("Lanczos did not converge in {} restarts", opts.max_restarts);
            }
            let vals = order.iter().take(k).map(|&c| theta[c]).collect();
            return Ok((vals, ritz, restart));
        }
        // Thick restart: the kept Ritz vectors (H becomes their Ritz values on the diagonal),
        // then the residual direction. The arrow entries coupling them to the residual are
        // recomputed by the Gram-Schmidt inner products of the next expansion step.
        let residual: Vec<f64> = w.iter().map(|x| x / beta).collect();
        for row in h.iter_mut() {
            row.iter_mut().for_each(|x| *x = 0.0);
        }
        for (i, &c) in order.iter().take(keep).enumerate() {
            h[i][i] = theta[c];
        }
        basis = ritz;
        basis.push(residual);
    }
    unreachable!("the loop returns at its last restart")
}

/// Chooses `t` maximising the Pearson correlation of diffusion and graph distances.
fn choose_t(
    n: usize,
    dijkstra: &(dyn Fn(u32, &mut Vec<f64>) + Sync),
    base: &[f64],
    lambdas: &[f64],
    opts: &Options,
) -> (f64, f64) {
    let dims = lambdas.len();
    let mut rng = XorShiftRng::seed_from_u64(opts.seed ^ 0x5eed);
    let mut pick = || (rng.next_u64() % n as u64) as u32;
    let sources: Vec<u32> = (0..opts.pairs).map(|_| pick()).collect();
    let targets: Vec<u32> = (0..opts.pairs).map(|_| pick()).collect();
    let mut dist = Vec::new();
    let mut geo = Vec::new();
    let mut diffs = Vec::new(); // squared coordinate differences per pair
    for &s in &sources {
        dijkstra(s, &mut dist);
        for &t in &targets {
            if s == t {
                continue;
            }
            geo.push(dist[t as usize]);
            let (a, b) = (
                &base[s as usize * dims..][..dims],
                &base[t as usize * dims..][..dims],
            );
            diffs.push(
                a.iter()
                    .zip(b)
                    .map(|(x, y)| (x - y) * (x - y))
                    .collect::<Vec<f64>>(),
            );
        }
    }
    let logs: Vec<f64> = lambdas
        .iter()
        .map(|l| l.max(f64::MIN_POSITIVE).ln())
        .collect();
    let pearson_at = |log10_t: f64| {
        let t = 10f64.powf(log10_t);
        let w: Vec<f64> = logs.iter().map(|l| (2.0 * t * l).exp()).collect();
        let dd: Vec<f64> = diffs
            .iter()
            .map(|d| d.iter().zip(&w).map(|(x, y)| x * y).sum::<f64>().sqrt())
            .collect();
        pearson(&dd, &geo)
    };
    let mut best = (0.0, f64::NEG_INFINITY);
    let steps = 350;
    for i in 0..=steps {
        let x = 7.0 * i as f64 / steps as f64;
        let p = pearson_at(x);
        if p > best.1 {
            best = (x, p);
        }
    }
    // Golden-section refinement around the best grid point.
    let h = 7.0 / steps as f64;
    let (mut lo, mut hi) = ((best.0 - h).max(0.0), (best.0 + h).min(7.0));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..40 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if pearson_at(a) > pearson_at(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    let x = 0.5 * (lo + hi);
    let p = pearson_at(x);
    if p > best.1 {
        (10f64.powf(x), p)
    } else {
        (10f64.powf(best.0), best.1)
    }
}

/// Pearson correlation of two samples.
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa == 0.0 || sbb == 0.0 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// How a table is laid out (the core's table versions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum TableLayout {
    /// Version 2: blocks of `c x c` map cells with one entry per connected free piece of a
    /// block (coarse and still exact about walls).
    Pieces,
    /// Version 1: one entry per `c x c` block, from the node nearest its centre (a cell may
    /// get coordinates from across a wall).
    Uniform,
}

/// Table layout options.
#[derive(Clone, Copy, Debug)]
pub struct TableOptions {
    /// Element encoding.
    pub kind: ElementKind,
    /// Map cells per block along each axis (1: full resolution; 0: the smallest factor whose
    /// table fits in `max_bytes`).
    pub coarsen: u16,
    /// Size budget of an automatically coarsened table (0: [`TableOptions::budget`]'s rule).
    pub max_bytes: usize,
    /// Layout.
    pub layout: TableLayout,
    /// Most memory a bake may use (estimated before it starts; `bake::bake_memory`).
    pub max_memory: usize,
    /// What the diffusion map is computed on.
    pub basis: BasisChoice,
    /// The hash of the map's packed grid, recorded in the table (versions 3 and 4: the table
    /// is bound to its map); `bake::bake_diffusion` sets it.
    pub map_hash: Option<u32>,
    /// The cell (column, row) whose connected component of free cells the table covers; the
    /// largest component when `None` or when the cell is occupied. A scenario's bake gives
    /// its start (issue 42: a start outside the largest component had no coordinates).
    pub keep: Option<(u16, u16)>,
}

/// What the diffusion map is computed on (`bake::Basis`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum BasisChoice {
    /// Cells on maps of at most 65,536 free cells, the table's pieces on larger ones.
    #[default]
    Auto,
    /// Every free cell (memory and time grow with the map).
    Cells,
    /// The table's pieces ([`crate::metric::diffusion::aggregate`]).
    Pieces,
}

/// The default size budget of a map of up to 65,536 cells: 128 KiB, the budget for the office
/// map in firmware. A 100 x 100 map then gets a full-resolution piece table (2 x 2 blocks when
/// it must), a 200 x 200 map 4 x 4 blocks; `bake` prints the error against full resolution.
pub const DEFAULT_MAX_BYTES: usize = 128 * 1024;

/// The default memory limit of a bake: 2 GiB.
pub const DEFAULT_MAX_MEMORY: usize = 2 << 30;

impl Default for TableOptions {
    fn default() -> Self {
        Self {
            kind: ElementKind::I16,
            coarsen: 0,
            max_bytes: 0,
            layout: TableLayout::Pieces,
            max_memory: DEFAULT_MAX_MEMORY,
            basis: BasisChoice::Auto,
            map_hash: None,
            keep: None,
        }
    }
}

/// The connected free pieces of every `block x block` block of a graph's cells.
#[derive(Clone, Debug)]
pub struct Pieces {
    /// Block side in cells.
    pub block: u32,
    /// Per map cell (row-major): its piece in its block, 1..=15, or 0 (no node).
    pub piece: Vec<u8>,
    /// Per entry (block by block, pieces in order): the graph nodes of the piece.
    pub members: Vec<Vec<u32>>,
}

impl Pieces {
    /// Splits every block into the pieces its cells form with the graph's edges inside the
    /// block. A block with more than 15 pieces (not possible below 6 x 6 blocks) merges the
    /// rest into its 15th.
    pub fn of(graph: &GridGraph, block: u32) -> Self {
        let (cols, rows, b) = (graph.cols, graph.rows, block.max(1));
        let mut piece = vec![0u8; (cols * rows) as usize];
        let mut members: Vec<Vec<u32>> = Vec::new();
        let mut stack = Vec::new();
        for br in 0..rows.div_ceil(b) {
            for bc in 0..cols.div_ceil(b) {
                let (c0, r0) = (bc * b, br * b);
                let (c1, r1) = ((c0 + b).min(cols), (r0 + b).min(rows));
                let inside = |cell: u32| {
                    let (c, r) = (cell % cols, cell / cols);
                    (c0..c1).contains(&c) && (r0..r1).contains(&r)
                };
                let mut count = 0u8;
                for r in r0..r1 {
                    for c in c0..c1 {
                        let cell = r * cols + c;
                        let node = graph.node_of_cell[cell as usize];
                        if node == u32::MAX || piece[cell as usize] != 0 {
                            continue;
                        }
                        if count < 15 {
                            count += 1;
                            members.push(Vec::new());
                        }
                        let group = members.last_mut().expect("a piece was pushed");
                        piece[cell as usize] = count;
                        group.push(node);
                        stack.push(node);
                        while let Some(n) = stack.pop() {
                            for (m, _) in graph.neighbours(n) {
                                let mc = graph.cell_of_node[m as usize];
                                if inside(mc) && piece[mc as usize] == 0 {
                                    piece[mc as usize] = count;
                                    group.push(m);
                                    stack.push(m);
                                }
                            }
                        }
                    }
                }
            }
        }
        Self {
            block: b,
            piece,
            members,
        }
    }

    /// The largest distance, in diffusion coordinates, from a member of an entry to the
    /// entry's mean: the most the table can be off for a cell of that entry.
    pub fn spread(map: &DiffusionMap, nodes: &[u32]) -> f64 {
        let mean = Self::mean(map, nodes);
        nodes
            .iter()
            .map(|&n| {
                map.node(n)
                    .iter()
                    .zip(&mean)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max)
    }

    /// The mean coordinates of some nodes.
    pub fn mean(map: &DiffusionMap, nodes: &[u32]) -> Vec<f64> {
        let mut m = vec![0.0; map.dims];
        for &n in nodes {
            for (acc, v) in m.iter_mut().zip(map.node(n)) {
                *acc += v;
            }
        }
        let k = nodes.len().max(1) as f64;
        m.iter_mut().for_each(|v| *v /= k);
        m
    }

    /// Splits entries whose [`Pieces::spread`] exceeds `tol` (each block keeps at most 15):
    /// the widest entry of a block is cut in two at the median of its widest coordinate,
    /// until every entry is within `tol` or the block is full. Cells keep their block; an
    /// entry may then hold part of a connected piece (never cells of two pieces).
    pub fn refine(&self, map: &DiffusionMap, graph: &GridGraph, tol: f64) -> Pieces {
        let mut piece = vec![0u8; self.piece.len()];
        let mut members = Vec::with_capacity(self.members.len());
        // Entries come block by block; regroup them per block.
        let mut at = 0;
        let cols = graph.cols;
        let block_of = |n: u32| {
            let cell = graph.cell_of_node[n as usize];
            ((cell / cols) / self.block, (cell % cols) / self.block)
        };
        while at < self.members.len() {
            let b = block_of(self.members[at][0]);
            let mut end = at;
            while end < self.members.len() && block_of(self.members[end][0]) == b {
                end += 1;
            }
            let mut group: Vec<(f64, Vec<u32>)> = self.members[at..end]
                .iter()
                .map(|m| (Self::spread(map, m), m.clone()))
                .collect();
            while group.len() < 15 {
                let (i, &(w, _)) = group
                    .iter()
                    .enumerate()
                    .max_by(|a, b| a.1.0.total_cmp(&b.1.0))
                    .expect("a block has an entry");
                if w <= tol || group[i].1.len() < 2 {
                    break;
                }
                let (_, nodes) = group.swap_remove(i);
                // The widest coordinate, split at its median.
                let d = (0..map.dims)
                    .max_by(|&x, &y| {
                        let range = |k: usize| {
                            let (lo, hi) = nodes.iter().fold((f64::MAX, f64::MIN), |(l, h), &n| {
                                (l.min(map.node(n)[k]), h.max(map.node(n)[k]))
                            });
                            hi - lo
                        };
                        range(x).total_cmp(&range(y))
                    })
                    .unwrap_or(0);
                let mut sorted = nodes;
                sorted.sort_by(|&a, &b| map.node(a)[d].total_cmp(&map.node(b)[d]));
                let right = sorted.split_off(sorted.len() / 2);
                group.push((Self::spread(map, &sorted), sorted));
                group.push((Self::spread(map, &right), right));
            }
            // Keep the entries in a stable order (by their first cell) for a repeatable bake.
            group.sort_by_key(|(_, m)| m.iter().map(|&n| graph.cell_of_node[n as usize]).min());
            for (q, (_, nodes)) in group.into_iter().enumerate() {
                for &n in &nodes {
                    piece[graph.cell_of_node[n as usize] as usize] = q as u8 + 1;
                }
                members.push(nodes);
            }
            at = end;
        }
        Pieces {
            block: self.block,
            piece,
            members,
        }
    }

    /// The largest [`Pieces::spread`] of any entry.
    pub fn max_spread(&self, map: &DiffusionMap) -> f64 {
        self.members
            .iter()
            .map(|m| Self::spread(map, m))
            .fold(0.0, f64::max)
    }

    /// Size of the table in bytes with `dims` elements of `elem` bytes per entry.
    pub fn table_len(&self, cols: u32, rows: u32, dims: usize, elem: usize) -> usize {
        let blocks = (cols.div_ceil(self.block) * rows.div_ceil(self.block)) as usize;
        TABLE_HEADER_LEN
            + 4
            + 2 * blocks
            + ((cols * rows) as usize).div_ceil(2)
            + self.members.len() * dims * elem
    }
}

impl TableOptions {
    /// Bytes the map's hash adds to a table (versions 3 and 4).
    fn stamp_len(&self) -> usize {
        if self.map_hash.is_some() { 4 } else { 0 }
    }

    /// The size budget of a table of a `cells`-cell map: `max_bytes`, or when that is 0,
    /// 128 KiB plus what the piece map (half a byte per cell) needs beyond 32 KiB. A map of
    /// up to 65,536 cells gets 128 KiB; a larger one keeps about 96 KiB for its entries.
    pub fn budget(&self, cells: usize) -> usize {
        if self.max_bytes > 0 {
            return self.max_bytes;
        }
        DEFAULT_MAX_BYTES + cells.div_ceil(2).saturating_sub(32 * 1024)
    }

    /// The pieces a large map's table holds (module [`crate::metric::diffusion::aggregate`]): those of the
    /// smallest block side whose table fits the budget, or of `coarsen` when it is set. An
    /// error names the knob when no block side up to 64 fits.
    pub fn aggregation(&self, edges: &CellEdges, dims: usize) -> Result<Aggregation> {
        let (cols, rows) = (edges.cols, edges.rows);
        let cells = cols as usize * rows as usize;
        let budget = self.budget(cells);
        let max_entries = bi_am_rrt::metric::PIECES_MAX_ENTRIES as usize;
        // Entries that fit with blocks of side b (None: not even the block index fits).
        let room = |b: u32| -> Option<usize> {
            let blocks = (cols.div_ceil(b) * rows.div_ceil(b)) as usize;
            let fixed = TABLE_HEADER_LEN + 4 + self.stamp_len() + 2 * blocks + cells.div_ceil(2);
            let room = budget.checked_sub(fixed)? / (dims * self.kind.size());
            Some(room.min(max_entries))
        };
        let sides: Vec<u32> = if self.coarsen > 0 {
            vec![self.coarsen as u32]
        } else {
            (1..=bi_am_rrt::metric::PIECES_MAX_BLOCK as u32).collect()
        };
        for &b in &sides {
            let Some(limit) = room(b) else { continue };
            // Every block holding a node holds a piece: skip sides that cannot fit.
            if edges.nodes / (b * b) as usize > limit {
                continue;
            }
            if let Some(agg) = Aggregation::of(edges, b, limit) {
                return Ok(agg);
            }
        }
        bail!(
            "no table of this {cols} x {rows} map fits {budget} bytes (blocks of {} cells at \
             most): raise --max-bytes{}",
            sides.last().copied().unwrap_or(1),
            if self.coarsen > 0 {
                " or --coarsen"
            } else {
                ""
            }
        )
    }

    /// [`Self::aggregation`], and with the automatic budget (`max_bytes` 0, every simulator
    /// command's) a map whose pieces do not fit it gets a larger one, doubled up to 64 times
    /// until they do (the host keeps the table in memory; an export for a chip gives its
    /// flash as the budget): the options used (`max_bytes` set when raised) and the pieces.
    pub fn fitted_aggregation(
        &self,
        edges: &CellEdges,
        dims: usize,
    ) -> Result<(Self, Aggregation)> {
        let auto = self.budget(edges.cols as usize * edges.rows as usize);
        let mut fitted = self.aggregation(edges, dims).map(|a| (*self, a));
        for factor in [2, 4, 8, 16, 32, 64] {
            if fitted.is_ok() || self.max_bytes != 0 {
                break;
            }
            let raised = Self {
                max_bytes: auto * factor,
                ..*self
            };
            fitted = raised.aggregation(edges, dims).map(|a| (raised, a));
        }
        fitted
    }

    /// The coarsening factor used for a graph of `cols x rows` cells with `dims` coordinates
    /// in the uniform layout.
    pub fn factor(&self, cols: u32, rows: u32, dims: usize) -> u16 {
        if self.coarsen > 0 {
            return self.coarsen;
        }
        let size = |c: u32| {
            TABLE_HEADER_LEN
                + self.stamp_len()
                + (cols.div_ceil(c) * rows.div_ceil(c)) as usize * dims * self.kind.size()
        };
        let budget = self.budget((cols * rows) as usize);
        (1..=64u32).find(|&c| size(c) <= budget).unwrap_or(64) as u16
    }

    /// The entries of a graph's table: the connected pieces of `coarsen x coarsen` blocks,
    /// refined where they spread widest, as far as `max_bytes` allows; with `coarsen` 0, the
    /// block side (1..=8) whose refined table is most precise within `max_bytes` (full
    /// resolution when it fits).
    pub fn pieces(&self, graph: &GridGraph, map: &DiffusionMap) -> Pieces {
        let dims = map.dims;
        let fits = |p: &Pieces| {
            p.members.len() <= bi_am_rrt::metric::PIECES_MAX_ENTRIES as usize
                && p.table_len(graph.cols, graph.rows, dims, self.kind.size()) + self.stamp_len()
                    <= self.budget((graph.cols * graph.rows) as usize)
        };
        // The most precise refinement of block side `b` that fits (None if even the
        // unrefined pieces do not).
        let best_for = |b: u32| -> Option<(f64, Pieces)> {
            let base = Pieces::of(graph, b);
            if !fits(&base) {
                return None;
            }
            let top = base.max_spread(map);
            let (mut lo, mut hi) = (0.0f64, top);
            let mut best = (top, base.clone());
            for _ in 0..24 {
                let mid = 0.5 * (lo + hi);
                let r = base.refine(map, graph, mid);
                if fits(&r) {
                    best = (r.max_spread(map), r);
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            Some(best)
        };
        if self.coarsen > 0 {
            let b = self.coarsen as u32;
            return best_for(b).map_or_else(|| Pieces::of(graph, b), |(_, p)| p);
        }
        let full = Pieces::of(graph, 1);
        if fits(&full) {
            return full;
        }
        (2..=8u32)
            .filter_map(best_for)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(full, |(_, p)| p)
    }
}

/// The element scale of a table of `map`'s coordinates.
fn element_scale(map: &DiffusionMap, kind: ElementKind) -> f32 {
    let max_abs = map.coords.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    match kind {
        ElementKind::I16 => (max_abs / 32767.0).max(f64::MIN_POSITIVE) as f32,
        ElementKind::F32 => 1.0,
    }
}

impl TableOptions {
    /// The header of a pieces table (version 3 with `map_hash`, else 2) of `map` on a map of
    /// `(cols, rows, cell)` in blocks of `block` cells with `entries` entries.
    fn piece_header(
        &self,
        map: &DiffusionMap,
        (cols, rows, cell): (u32, u32, f32),
        block: u32,
        entries: usize,
    ) -> Result<TableHeader> {
        Ok(TableHeader {
            map_hash: self.map_hash,
            kind: self.kind,
            dims: map.dims as u16,
            cols: u16::try_from(cols).context("map too wide for a table")?,
            rows: u16::try_from(rows).context("map too tall for a table")?,
            cell_size: cell,
            scale: element_scale(map, self.kind),
            layout: bi_am_rrt::metric::Layout::Pieces {
                block: block as u16,
                entries: u32::try_from(entries).context("too many pieces")?,
            },
        })
    }
}

/// Writes the pieces table (version 3 when `opts.map_hash` is set) of a diffusion map computed on the pieces `agg`
/// ([`crate::metric::diffusion::aggregate`]): one entry per piece, its coordinates as computed.
pub fn aggregated_table_bytes(
    edges: &CellEdges,
    agg: &Aggregation,
    map: &DiffusionMap,
    opts: &TableOptions,
) -> Result<Vec<u8>> {
    let shape = (edges.cols, edges.rows, edges.cell);
    piece_table(
        opts,
        map,
        shape,
        agg.block,
        &agg.piece,
        agg.count,
        |e, coords| {
            for (slot, v) in coords.iter_mut().zip(map.node(e)) {
                *slot = *v as f32;
            }
            true
        },
    )
}

/// Writes a pieces table of `map` ([`TableOptions::piece_header`]): `piece` gives each map
/// cell's piece in its block, `coords(entry, out)` each entry's coordinates (false:
/// unreachable).
fn piece_table(
    opts: &TableOptions,
    map: &DiffusionMap,
    shape: (u32, u32, f32),
    block: u32,
    piece: &[u8],
    entries: usize,
    coords: impl FnMut(u32, &mut [f32]) -> bool,
) -> Result<Vec<u8>> {
    let header = opts.piece_header(map, shape, block, entries)?;
    let mut out = vec![0u8; header.table_len().context("table too large")?];
    let cols = shape.0;
    let written = bi_am_rrt::metric::write_piece_table(
        &header,
        &mut out,
        |c, r| piece[(r as u32 * cols + c as u32) as usize],
        coords,
    )
    .context("writing the table: pieces and header disagree")?;
    out.truncate(written);
    Ok(out)
}

/// Writes the table of a diffusion map (see [`TableLayout`] for what a coarse table holds).
pub fn table_bytes(graph: &GridGraph, map: &DiffusionMap, opts: &TableOptions) -> Result<Vec<u8>> {
    let scale = element_scale(map, opts.kind);
    if opts.layout == TableLayout::Pieces {
        let p = opts.pieces(graph, map);
        let shape = (graph.cols, graph.rows, graph.cell);
        let entries = p.members.len();
        return piece_table(opts, map, shape, p.block, &p.piece, entries, |e, coords| {
            // The entry's mean coordinates: the point nearest all of its cells.
            let nodes = &p.members[e as usize];
            for (slot, v) in coords.iter_mut().zip(Pieces::mean(map, nodes)) {
                *slot = v as f32;
            }
            !nodes.is_empty()
        });
    }
    let c = opts.factor(graph.cols, graph.rows, map.dims) as u32;
    let cols = graph.cols.div_ceil(c) as u16;
    let rows = graph.rows.div_ceil(c) as u16;
    let header = TableHeader {
        map_hash: opts.map_hash,
        kind: opts.kind,
        dims: map.dims as u16,
        cols,
        rows,
        cell_size: graph.cell * c as f32,
        scale,
        layout: bi_am_rrt::metric::Layout::Uniform,
    };
    let mut out = vec![0u8; header.table_len().context("table too large")?];
    let written = write_table(&header, &mut out, |tc, tr, coords| {
        let node = representative(graph, tc as u32, tr as u32, c);
        match node {
            Some(nd) => {
                for (slot, v) in coords.iter_mut().zip(map.node(nd)) {
                    *slot = *v as f32;
                }
                true
            }
            None => false,
        }
    })
    .context("writing the table")?;
    out.truncate(written);
    Ok(out)
}

/// The node of the block of `c x c` map cells at table cell `(tc, tr)` nearest its centre.
fn representative(graph: &GridGraph, tc: u32, tr: u32, c: u32) -> Option<u32> {
    let centre = (
        (tc * c) as f64 + c as f64 / 2.0,
        (tr * c) as f64 + c as f64 / 2.0,
    );
    let mut best: Option<(f64, u32)> = None;
    for r in tr * c..((tr + 1) * c).min(graph.rows) {
        for col in tc * c..((tc + 1) * c).min(graph.cols) {
            let node = graph.node_of_cell[(r * graph.cols + col) as usize];
            if node == u32::MAX {
                continue;
            }
            let d = (col as f64 + 0.5 - centre.0).powi(2) + (r as f64 + 0.5 - centre.1).powi(2);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, node));
            }
        }
    }
    best.map(|(_, n)| n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::OwnedGrid;

    /// Issue 42: a 4,096-cell building at 0.05 m was refused by `run` ("no table fits
    /// 8486912 bytes: raise --max-bytes", a flag `run` does not have). A map of 2,048 x 2,048
    /// cells whose 1-cell corridors join in pairs only every other block row (in alternate
    /// pairs) makes more pieces than the default budget holds at any block side: the
    /// automatic budget is raised until they fit; a budget the user gave is kept, and refused
    /// as before.
    #[test]
    fn regression_a_map_whose_pieces_outgrow_the_default_table_gets_a_larger_one() {
        let side = 2048u16;
        let g = OwnedGrid::from_fn(side, side, 0.05, |c, r| {
            let (c, r) = (u32::from(c), u32::from(r));
            // Walls at even columns; a wall at 4k opens at row 63 of every 256, one at
            // 4k + 2 at row 191.
            c % 2 == 0 && !((c % 4 == 0 && r % 256 == 63) || (c % 4 == 2 && r % 256 == 191))
        })
        .unwrap();
        let edges = crate::metric::diffusion::aggregate::CellEdges::build(&g.grid());
        let dims = Options::default().eigenpairs - 1;
        let auto = TableOptions::default();
        assert!(
            auto.aggregation(&edges, dims).is_err(),
            "the default budget fits: no test"
        );
        let (fitted, agg) = auto.fitted_aggregation(&edges, dims).unwrap();
        let cells = usize::from(side) * usize::from(side);
        assert!(
            fitted.max_bytes > auto.budget(cells),
            "{}",
            fitted.max_bytes
        );
        assert!(agg.count > 0);
        let given = TableOptions {
            max_bytes: auto.budget(cells),
            ..auto
        };
        assert!(given.fitted_aggregation(&edges, dims).is_err());
    }

    /// The eigenvalues against faer's dense solver on a small map.
    #[test]
    fn matches_a_dense_eigensolver() {
        let g = OwnedGrid::from_fn(16, 14, 1.0, |c, r| (c == 7 && r < 10) || (r == 5 && c > 10))
            .unwrap();
        let graph = GridGraph::build(&g.grid());
        let n = graph.len();
        let map = diffusion_map(&graph, &Options::default()).unwrap();
        let rep = &map.report;
        assert!(rep.orthogonality < 1e-12, "{}", rep.orthogonality);
        assert!(
            rep.residuals.iter().all(|&r| r < 1e-10),
            "{:?}",
            rep.residuals
        );
        // Dense E, built independently from the definition.
        let kernel = |w: f64| (-(w * w) / 2.0).exp();
        let mut a = Mat::<f64>::zeros(n, n);
        for i in 0..n as u32 {
            for (j, w) in graph.neighbours(i) {
                a[(i as usize, j as usize)] = kernel(w);
            }
        }
        let d: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a[(i, j)]).sum()).collect();
        let a2 = Mat::<f64>::from_fn(n, n, |i, j| {
            let a1 = 0.5 * a[(i, j)] + if i == j { 0.5 * d[i] } else { 0.0 };
            a1 / (d[i] * d[j])
        });
        let d2: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a2[(i, j)]).sum()).collect();
        let e = Mat::<f64>::from_fn(n, n, |i, j| a2[(i, j)] / (d2[i] * d2[j]).sqrt());
        let dense = e.self_adjoint_eigenvalues(Side::Lower).unwrap();
        let top: Vec<f64> = dense.iter().rev().take(11).copied().collect();
        assert!((top[0] - 1.0).abs() < 1e-12);
        for (x, y) in rep.eigenvalues.iter().zip(&top) {
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
        assert!(rep.pearson > 0.5, "pearson {}", rep.pearson);
        assert_eq!(map.dims, 10);
    }

    #[test]
    fn table_round_trip_and_quantisation_bound() {
        let g = OwnedGrid::from_fn(20, 20, 1.0, |c, r| c == 10 && r > 3).unwrap();
        let graph = GridGraph::build(&g.grid());
        let map = diffusion_map(&graph, &Options::default()).unwrap();
        let full = table_bytes(
            &graph,
            &map,
            &TableOptions {
                kind: ElementKind::F32,
                coarsen: 1,
                ..TableOptions::default()
            },
        )
        .unwrap();
        let fine = TableOptions {
            coarsen: 1,
            ..TableOptions::default()
        };
        let q = table_bytes(&graph, &map, &fine).unwrap();
        let (tf, tq) = (
            bi_am_rrt::DiffusionTable::new(&full).unwrap(),
            bi_am_rrt::DiffusionTable::new(&q).unwrap(),
        );
        use bi_am_rrt::Metric;
        let bound = (map.dims as f32).sqrt() * tq.header().scale;
        for a in 0..graph.len() as u32 {
            for b in (0..graph.len() as u32).step_by(7) {
                let (pa, pb) = (graph.position(a), graph.position(b));
                let exact = map.distance(a, b) as f32;
                assert!((tf.distance(pa, pb) - exact).abs() <= 1e-4 * exact.max(1.0));
                assert!(
                    (tq.distance(pa, pb) - exact).abs() <= bound + 1e-4 * exact,
                    "{a} {b}"
                );
            }
        }
        // Cells off the graph are unreachable.
        assert_eq!(
            tq.distance(bi_am_rrt::Point::new(10.5, 10.5), graph.position(0)),
            f32::INFINITY
        );
    }

    /// Issue 8: a coarse table gave cells coordinates from across a wall. With pieces, the
    /// cells on either side of a wall inside one block read different entries, and the table
    /// is far closer to full precision than the uniform one of the same block side.
    #[test]
    fn regression_piece_tables_never_read_across_a_wall() {
        use bi_am_rrt::Metric;
        // A wall along column 9 with a gap at the bottom: blocks of 4 straddle it.
        let g = OwnedGrid::from_fn(24, 24, 1.0, |c, r| c == 9 && r < 21).unwrap();
        let graph = GridGraph::build(&g.grid());
        let map = diffusion_map(&graph, &Options::default()).unwrap();
        let pieces = Pieces::of(&graph, 4);
        let cell = |c: u32, r: u32| (r * 24 + c) as usize;
        // Rows 0-19: blocks the wall splits (rows 20-23 hold the gap: one piece there).
        for r in 0..20 {
            assert_ne!(
                pieces.piece[cell(8, r)],
                pieces.piece[cell(10, r)],
                "row {r}"
            );
            assert_eq!(pieces.piece[cell(9, r)], 0, "the wall has no entry");
        }
        assert_eq!(pieces.piece[cell(8, 22)], pieces.piece[cell(10, 22)]);
        let err = |layout| {
            let t = table_bytes(
                &graph,
                &map,
                &TableOptions {
                    coarsen: 4,
                    layout,
                    max_bytes: 0,
                    ..TableOptions::default()
                },
            )
            .unwrap();
            let t = bi_am_rrt::DiffusionTable::new(&t).unwrap();
            let mut worst = 0.0f64;
            for a in (0..graph.len() as u32).step_by(3) {
                for b in (0..graph.len() as u32).step_by(5) {
                    let got = t.distance(graph.position(a), graph.position(b)) as f64;
                    worst = worst.max((got - map.distance(a, b)).abs());
                }
            }
            worst
        };
        let (pieces_err, uniform_err) = (err(TableLayout::Pieces), err(TableLayout::Uniform));
        assert!(
            pieces_err * 2.0 < uniform_err,
            "{pieces_err} vs {uniform_err}"
        );
        // Refining within a budget only lowers the spread.
        let refined = pieces.refine(&map, &graph, 0.0);
        assert!(refined.max_spread(&map) <= pieces.max_spread(&map));
        assert!(refined.members.len() > pieces.members.len());
    }

    #[test]
    fn automatic_coarsening_fits_the_budget() {
        let o = TableOptions {
            max_bytes: 192 * 1024,
            ..TableOptions::default()
        };
        assert_eq!(o.factor(100, 100, 10), 2);
        assert_eq!(o.factor(200, 200, 10), 3);
        assert_eq!(o.factor(30, 30, 10), 1);
        assert_eq!(TableOptions { coarsen: 1, ..o }.factor(200, 200, 10), 1);
    }
}
