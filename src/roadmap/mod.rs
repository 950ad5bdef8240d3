//! A roadmap baked with the map, for the first solution (beyond the paper; the `roadmap`
//! tactic, feature `roadmap`). Algorithm 1 grows both trees from nothing until they meet: on
//! the reference maps that is about ten expansions and thirty segment tests before the goal
//! joins. The static map does not change between queries, so the shape of its shortest paths
//! can be baked, as the assisting metric's table is: a reduced visibility graph, a node just
//! off each convex corner of the occupied cells and an edge between two nodes that see each
//! other over a segment tangent to the obstacle at both ends (a shortest path bends only at
//! convex corners). `host-sim` bakes it (`host_sim::metric::roadmap`); [`write()`] makes the
//! bytes anywhere, and they can sit in flash (`host-sim export` writes them beside the grid
//! and the table).
//!
//! When a goal is set, the planner's first step (the `roadmap` tactic, [`crate::Tactics`])
//! joins the goal over the straight segment when it is free, else searches the roadmap once
//! (`open`, `resume`): the root and the goal each attach to their nearest nodes (tangent
//! at the node; the root's tested first, the goal's only once a way the search settles on
//! ends there: a node the goal does not see is dropped and the search goes on without it; an
//! end that sees none of its nearest nodes, or whose nodes the search cannot reach, takes the
//! next nearest, as in a maze whose nearest corners lie behind the walls), a
//! weighted A* joins them, every edge of the path found is tested free as any tree edge is
//! (the dynamic obstacles, live cells and the robot's body count), and the path becomes a
//! branch of the reverse tree that meets the forward tree's root (paper Algorithm 1's meet
//! and graft). From there the planner goes on as ever: rewiring shortens the path. When the
//! roadmap has no path or an edge is blocked, nothing is kept and the trees search as they
//! would have. A call that ends first leaves the search where it stands
//! (`Stage`) and the next call takes it up before any tree step, so a caller's short calls
//! still get the roadmap's path (the path's ends are then tested again: the root or an
//! obstacle may have moved). The search needs no memory of its own: the reverse arena's last
//! free slots are its scratch (`Tree::spare`), kept from call to call while the trees wait,
//! and the path it finds waits in the last of them while the branch is built in the first (a
//! path of any length, up to half the free slots).
//!
//! # Format (version 1, little-endian)
//!
//! | bytes | field |
//! |---|---|
//! | 4 | magic `BRM1` |
//! | 2, 2 | version (1), reserved (0) |
//! | 4 | hash of the map it was baked for ([`crate::metric::map_hash`]) |
//! | 2, 2, 4 | that map's columns, rows and cell size (`f32`, metres) |
//! | 4, 4 | nodes `R`, directed edges `E` |
//! | 8 R | each node's position, `x` then `y` (`f32`, metres), in order of `x` (then `y`) |
//! | R, padded to 4 | each node's corner: bit 0 the diagonal into the corner's occupied cell points to `+x`, bit 1 to `+y`; 4 for a node without a corner |
//! | 4 (R + 1) | where each node's edges start in the edge list (`u32`), then `E` |
//! | 2 E, padded to 4 | the edges' far nodes (`u16`), each edge listed from both ends |

use crate::clock::{Clock, Meter};
use crate::error::RoadmapError;
use crate::expand::Env;
use crate::geometry::Point;
use crate::metric::Metric;
use crate::slots::{rd, units, wr};

/// The magic bytes a roadmap starts with.
pub const MAGIC: [u8; 4] = *b"BRM1";
/// The format version this build reads and writes.
pub const VERSION: u16 = 1;
/// Header bytes.
pub const HEADER_BYTES: usize = 28;
/// A node's corner byte when the node has no corner (any direction is tangent).
pub const NO_CORNER: u8 = 4;
/// How far, in cells, a node with a corner stands from it, along the corner's diagonal away
/// from its occupied cell (part of the format: [`Roadmap::tangent`] finds the corner so).
pub const NODE_OFFSET: f32 = 0.6;
/// Most roadmap nodes (ids are `u16`).
pub const MAX_NODES: usize = u16::MAX as usize - 1;

/// Nodes the root and the goal each consider, nearest first (tangent at the node).
const ATTACH_CANDIDATES: usize = 8;
/// Nodes the root attaches to, at most: the first of its candidates it sees (each tested
/// before the search opens). The goal's candidates are tested only when a way uses them.
/// Three, not six: each is a segment test before the search, and more open starts drew the
/// search wider (house384 leg 1 closed 51 nodes with six); with [`WEIGHT`] the first paths
/// were shorter on most maps (`docs/notebook/first-solution.md`, twenty-ninth session).
const ATTACH: usize = 3;
/// Times an end's candidates are taken again, the next [`ATTACH_CANDIDATES`] nearest, when it
/// sees none of those it had (an end beside a wall, in a maze whose nearest corners are
/// behind the walls): up to `ATTACH_CANDIDATES * (1 + WIDEN)` nodes an end.
const WIDEN: u8 = 3;
/// The A* heuristic's weight: the straight distance to the goal counts 1.5 times, so the
/// search pops far fewer nodes on a dense roadmap (a map of many small obstacles has 20-40
/// edges a node) for a first path at most 1.5 times the roadmap's shortest (rewiring shortens
/// it from the first call on). Weight 2 went greedily into the pockets beside the goal's
/// direction as often as it saved pops, for first paths 2-8 % longer on the buildings (with
/// [`ATTACH`] 3; house384, depot, rooms512, city1024). Measured on the reference, nav2 and
/// generated maps: `docs/notebook/first-solution.md`.
const WEIGHT: f32 = 1.5;
const fn pad4(n: usize) -> usize {
    n.saturating_add(3) & !3usize
}

/// Bytes of a roadmap of `nodes` nodes and `edges` directed edges.
pub const fn bytes_needed(nodes: usize, edges: usize) -> usize {
    HEADER_BYTES
        .saturating_add(nodes.saturating_mul(8))
        .saturating_add(pad4(nodes))
        .saturating_add(nodes.saturating_add(1).saturating_mul(4))
        .saturating_add(pad4(edges.saturating_mul(2)))
}

/// A roadmap read in place from its bytes (module docs), validated once when made.
#[derive(Clone, Copy, Debug)]
pub struct Roadmap<'a> {
    map_hash: u32,
    grid: (u16, u16, f32),
    nodes: usize,
    edges: usize,
    pos: &'a [u8],
    corner: &'a [u8],
    first: &'a [u8],
    far: &'a [u8],
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s = b.get(at..at.checked_add(2)?)?;
    Some(u16::from_le_bytes([*s.first()?, *s.get(1)?]))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([
        *s.first()?,
        *s.get(1)?,
        *s.get(2)?,
        *s.get(3)?,
    ]))
}

impl<'a> Roadmap<'a> {
    /// Reads and validates a roadmap: magic, version, sizes, every edge list in order and in
    /// range, every position finite. O(nodes + edges).
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, RoadmapError> {
        if bytes.len() < HEADER_BYTES {
            return Err(RoadmapError::Truncated);
        }
        if bytes.get(..4) != Some(&MAGIC[..]) {
            return Err(RoadmapError::BadMagic);
        }
        if u16_at(bytes, 4) != Some(VERSION) {
            return Err(RoadmapError::UnsupportedVersion);
        }
        let field = |at| u32_at(bytes, at).ok_or(RoadmapError::Truncated);
        let map_hash = field(8)?;
        let cols = u16_at(bytes, 12).ok_or(RoadmapError::Truncated)?;
        let rows = u16_at(bytes, 14).ok_or(RoadmapError::Truncated)?;
        let cell = f32::from_bits(field(16)?);
        let nodes = usize::try_from(field(20)?).map_err(|_| RoadmapError::BadHeader)?;
        let edges = usize::try_from(field(24)?).map_err(|_| RoadmapError::BadHeader)?;
        if nodes > MAX_NODES || edges > usize::MAX / 8 {
            return Err(RoadmapError::BadHeader);
        }
        if bytes.len() != bytes_needed(nodes, edges) {
            return Err(if bytes.len() < bytes_needed(nodes, edges) {
                RoadmapError::Truncated
            } else {
                RoadmapError::BadHeader
            });
        }
        let mut at = HEADER_BYTES;
        let mut take = |n: usize| {
            let s = bytes.get(at..at.saturating_add(n));
            at = at.saturating_add(n);
            s.ok_or(RoadmapError::Truncated)
        };
        let pos = take(nodes.saturating_mul(8))?;
        let corner = take(pad4(nodes))?;
        let first = take(nodes.saturating_add(1).saturating_mul(4))?;
        let far = take(pad4(edges.saturating_mul(2)))?;
        let r = Self {
            map_hash,
            grid: (cols, rows, cell),
            nodes,
            edges,
            pos,
            corner,
            first,
            far,
        };
        let mut prev = 0usize;
        let mut last_x = f32::NEG_INFINITY;
        for i in 0..nodes {
            let p = r.node(i).unwrap_or(Point::new(f32::NAN, f32::NAN));
            if !p.is_finite() || p.x < last_x || rd(corner, i, 0) > NO_CORNER {
                return Err(RoadmapError::BadHeader);
            }
            last_x = p.x;
            let (a, b) = r.span(i).ok_or(RoadmapError::BadHeader)?;
            if a != prev || b < a || b > edges {
                return Err(RoadmapError::BadHeader);
            }
            prev = b;
            for k in a..b {
                let j = r.far(k).ok_or(RoadmapError::BadHeader)?;
                if j >= nodes || j == i {
                    return Err(RoadmapError::BadHeader);
                }
            }
        }
        if prev != edges {
            return Err(RoadmapError::BadHeader);
        }
        Ok(r)
    }

    /// The hash of the map it was baked for ([`crate::metric::map_hash`] of the planner's
    /// [`crate::Map::metric_grid`]); the planner refuses a roadmap of another map.
    pub fn map_hash(&self) -> u32 {
        self.map_hash
    }

    /// Whether it was baked for `grid`: the same hash ([`crate::metric::map_hash`]: its cells
    /// and, for a robot body, the radius), columns, rows and cell size.
    pub fn fits(&self, grid: &crate::map::OccupancyGrid<'_>) -> bool {
        crate::metric::map_hash(grid) == Some(self.map_hash)
            && (grid.cols(), grid.rows()) == (self.grid.0, self.grid.1)
            && grid.cell_size().to_bits() == self.grid.2.to_bits()
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes
    }

    /// Whether it has no node.
    pub fn is_empty(&self) -> bool {
        self.nodes == 0
    }

    /// Number of edges (each counted once, though listed from both ends).
    pub fn edges(&self) -> usize {
        self.edges / 2
    }

    /// Node `i`'s position.
    pub fn node(&self, i: usize) -> Option<Point> {
        let at = i.checked_mul(8)?;
        let x = f32::from_bits(u32_at(self.pos, at)?);
        let y = f32::from_bits(u32_at(self.pos, at.checked_add(4)?)?);
        Some(Point::new(x, y))
    }

    /// Node `i`'s corner byte (module docs).
    pub fn corner(&self, i: usize) -> u8 {
        rd(self.corner, i, NO_CORNER)
    }

    /// Where node `i`'s edges start and end in the edge list.
    fn span(&self, i: usize) -> Option<(usize, usize)> {
        let a = u32_at(self.first, i.checked_mul(4)?)?;
        let b = u32_at(self.first, i.checked_add(1)?.checked_mul(4)?)?;
        Some((usize::try_from(a).ok()?, usize::try_from(b).ok()?))
    }

    fn far(&self, k: usize) -> Option<usize> {
        u16_at(self.far, k.checked_mul(2)?).map(usize::from)
    }

    /// The nodes node `i` has an edge to.
    pub fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let (a, b) = self.span(i).unwrap_or((0, 0));
        (a..b).filter_map(|k| self.far(k))
    }

    /// Whether the segment from `from` to node `i`'s corner passes the corner tangentially:
    /// its line does not cut into the corner's occupied cell (within 45 degrees of the
    /// diagonal into the cell, either way, it would). A shortest path arrives at a corner only
    /// so. The corner is [`NODE_OFFSET`] cells from the node along its diagonal; tested from
    /// the node itself, a segment along a corridor a cell wide would tilt by up to a third of
    /// the cell and fail.
    pub fn tangent(&self, i: usize, from: Point) -> bool {
        let c = self.corner(i);
        if c >= NO_CORNER {
            return true;
        }
        let Some(n) = self.node(i) else {
            return false;
        };
        let dx = if c & 1 != 0 { 1.0 } else { -1.0 };
        let dy = if c & 2 != 0 { 1.0 } else { -1.0 };
        let off = NODE_OFFSET * self.grid.2;
        let (ex, ey) = (n.x + off * dx - from.x, n.y + off * dy - from.y);
        let along = libm::fabsf(ex * dx + ey * dy);
        along * along <= (ex * ex + ey * ey) * 1.0001
    }
}

/// Writes a roadmap (module docs) of the map `grid` (the planner's [`crate::Map::metric_grid`]:
/// its hash, size and cell size are recorded) into `out`; returns the bytes written. Nodes
/// come in order of `x`. `first` has one entry
/// per node and one more (each node's edges start there in `far`; the last is `far.len()`);
/// every edge is listed from both ends. Errors as [`Roadmap::from_bytes`] would refuse it, or
/// [`RoadmapError::Truncated`] when `out` is shorter than [`bytes_needed`].
pub fn write(
    grid: &crate::map::OccupancyGrid<'_>,
    nodes: &[Point],
    corners: &[u8],
    first: &[u32],
    far: &[u16],
    out: &mut [u8],
) -> Result<usize, RoadmapError> {
    let n = bytes_needed(nodes.len(), far.len());
    if corners.len() != nodes.len() || first.len() != nodes.len().saturating_add(1) {
        return Err(RoadmapError::BadHeader);
    }
    let out = out.get_mut(..n).ok_or(RoadmapError::Truncated)?;
    out.fill(0);
    let mut at = 0usize;
    let mut put = |b: &[u8]| {
        let end = at.saturating_add(b.len());
        if let Some(s) = out.get_mut(at..end) {
            s.copy_from_slice(b);
        }
        at = end;
    };
    put(&MAGIC);
    put(&VERSION.to_le_bytes());
    put(&0u16.to_le_bytes());
    put(&crate::metric::map_hash(grid)
        .ok_or(RoadmapError::BadHeader)?
        .to_le_bytes());
    put(&grid.cols().to_le_bytes());
    put(&grid.rows().to_le_bytes());
    put(&grid.cell_size().to_bits().to_le_bytes());
    put(&u32::try_from(nodes.len()).unwrap_or(u32::MAX).to_le_bytes());
    put(&u32::try_from(far.len()).unwrap_or(u32::MAX).to_le_bytes());
    for p in nodes {
        put(&p.x.to_bits().to_le_bytes());
        put(&p.y.to_bits().to_le_bytes());
    }
    put(corners);
    let pad = pad4(corners.len()).saturating_sub(corners.len());
    put([0u8; 3].get(..pad).unwrap_or_default());
    for f in first {
        put(&f.to_le_bytes());
    }
    for j in far {
        put(&j.to_le_bytes());
    }
    Roadmap::from_bytes(out)?;
    Ok(n)
}

/// The search's scratch: the unused slots of an arena (module docs), one entry per roadmap
/// node in each array.
pub(crate) struct Scratch<'s> {
    /// Best known distance from the root (`x`) and the open set's key, that distance plus the
    /// straight distance to the goal (`y`).
    pub g: &'s mut [Point],
    /// The node it was reached from (`u16::MAX`: a node the root attached to).
    pub parent: &'s mut [u16],
    /// The open set's binary heap of node ids.
    pub heap: &'s mut [u16],
    /// Each node's heap slot plus one; 0 never opened, `u16::MAX` closed.
    pub slot: &'s mut [u16],
}

const CLOSED: u16 = u16::MAX;

const UNSEEN: Point = Point::new(f32::INFINITY, f32::INFINITY);

impl Scratch<'_> {
    fn key(&self, i: u16) -> f32 {
        rd(self.g, usize::from(i), UNSEEN).y
    }

    fn dist(&self, i: usize) -> f32 {
        rd(self.g, i, UNSEEN).x
    }

    /// Moves heap entry `k` up or down to its place (`len` entries).
    fn sift(&mut self, mut k: usize, len: usize) {
        // Up.
        while k > 0 {
            let up = k.saturating_sub(1) >> 1;
            let (a, b) = (rd(self.heap, k, 0), rd(self.heap, up, 0));
            if self.key(a) >= self.key(b) {
                break;
            }
            self.swap(k, up);
            k = up;
        }
        // Down.
        loop {
            let l = k.saturating_mul(2).saturating_add(1);
            if l >= len {
                break;
            }
            let r = l.saturating_add(1);
            let mut m = l;
            if r < len && self.key(rd(self.heap, r, 0)) < self.key(rd(self.heap, l, 0)) {
                m = r;
            }
            if self.key(rd(self.heap, m, 0)) >= self.key(rd(self.heap, k, 0)) {
                break;
            }
            self.swap(k, m);
            k = m;
        }
    }

    fn swap(&mut self, a: usize, b: usize) {
        let (x, y) = (rd(self.heap, a, 0), rd(self.heap, b, 0));
        wr(self.heap, a, y);
        wr(self.heap, b, x);
        wr(self.slot, usize::from(y), slot_of(a));
        wr(self.slot, usize::from(x), slot_of(b));
    }
}

fn slot_of(k: usize) -> u16 {
    u16::try_from(k.saturating_add(1)).unwrap_or(CLOSED)
}

/// An end's candidates: the nearest nodes tangent at the node, nearest first, with their
/// distances and whether the end was seen to see them (their segments tested free).
type Candidates = heapless::Vec<(u16, f32, bool), ATTACH_CANDIDATES>;

/// An end's candidates so far: the farthest taken (its squared distance and id: the next
/// ones are beyond it), and how many times they were taken again ([`WIDEN`]).
#[derive(Clone, Copy, Debug)]
struct Reach {
    beyond: (f32, u16),
    widened: u8,
}

/// The [`ATTACH_CANDIDATES`] nodes of `rm` nearest `p` whose segment from `p` is tangent at
/// the node and that lie beyond `reach` (farther, or as far with a higher id), nearest first,
/// with their distances; whether `p` sees them is tested later ([`resume`]). `reach` becomes
/// the farthest of them. The nodes come in order of `x`: the scan starts at `p.x` and widens
/// both ways until a column of nodes is farther in `x` alone than the farthest candidate kept.
#[inline(never)]
fn attach<C: Clock + ?Sized>(
    rm: &Roadmap<'_>,
    p: Point,
    reach: &mut Reach,
    meter: &Meter<'_, C>,
) -> Candidates {
    let beyond = reach.beyond;
    let mut near: heapless::Vec<(f32, u16), ATTACH_CANDIDATES> = heapless::Vec::new();
    let x = |i: usize| rm.node(i).map_or(f32::INFINITY, |n| n.x);
    // The first node with x >= p.x.
    let (mut lo, mut hi) = (0usize, rm.len());
    while lo < hi {
        let mid = lo.saturating_add(hi.saturating_sub(lo) >> 1);
        if x(mid) < p.x {
            lo = mid.saturating_add(1);
        } else {
            hi = mid;
        }
    }
    let (mut right, mut left) = (lo, lo);
    let mut visited = 0u32;
    loop {
        let worst = if near.is_full() {
            near.last().map_or(f32::INFINITY, |&(d, _)| d)
        } else {
            f32::INFINITY
        };
        let dr = (right < rm.len()).then(|| x(right) - p.x);
        let dl = (left > 0).then(|| p.x - x(left.saturating_sub(1)));
        let i = match (dr, dl) {
            (Some(a), Some(b)) if a <= b && a * a <= worst => {
                right = right.saturating_add(1);
                right.saturating_sub(1)
            }
            (Some(a), None) if a * a <= worst => {
                right = right.saturating_add(1);
                right.saturating_sub(1)
            }
            (_, Some(b)) if b * b <= worst => {
                left = left.saturating_sub(1);
                left
            }
            _ => break,
        };
        visited = visited.saturating_add(1);
        let Some(n) = rm.node(i) else { continue };
        let d2 = n.dist_sq(p);
        let id = u16::try_from(i).unwrap_or(u16::MAX);
        if d2 > worst || (d2, id) <= beyond || !rm.tangent(i, p) {
            continue;
        }
        let at = near.partition_point(|&(d, _)| d <= d2);
        if at < ATTACH_CANDIDATES {
            if near.is_full() {
                near.pop();
            }
            let _ = near.insert(at, (d2, id));
        }
    }
    meter.charge((visited >> 2).saturating_add(4));
    let mut out = Candidates::new();
    for &(d2, i) in &near {
        let _ = out.push((i, crate::geometry::sqrt(d2), false));
        reach.beyond = (d2, i);
    }
    out
}

/// Takes `list` again, the next nodes beyond `reach`, when it is empty and [`WIDEN`] allows:
/// whether it did.
fn widen<C: Clock + ?Sized>(
    rm: &Roadmap<'_>,
    p: Point,
    list: &mut Candidates,
    reach: &mut Reach,
    meter: &Meter<'_, C>,
) -> bool {
    if !list.is_empty() || reach.widened >= WIDEN {
        return false;
    }
    reach.widened = reach.widened.saturating_add(1);
    *list = attach(rm, p, reach, meter);
    !list.is_empty()
}

/// Where a roadmap search stands between two planner calls (the planner keeps it; the search's
/// scratch stays in the arena's last slots, which nothing else writes while it is open). A
/// call that ends before the search does leaves it here, and the next call takes it up where
/// it stopped: the trees do not grow meanwhile, so a caller's short calls lose nothing.
#[derive(Clone, Debug, Default)]
pub(crate) enum Stage {
    /// No search: no goal, no roadmap, or this goal's search has ended.
    #[default]
    Idle,
    /// A goal was set: the next call tests the straight segment to it.
    Due,
    /// The straight segment is blocked: the next call opens the search ([`open`]).
    Blocked,
    /// The A* is under way.
    Open(Search),
    /// A path of `len` nodes waits at the arena's end (`len` 0: the straight segment); its
    /// segments before `tested` were found free (counted from the goal's end, segment `k`
    /// joining path nodes `k - 1` and `k`, the goal and the root standing for nodes -1 and
    /// `len`). A call that takes it up tests its two ends again (the root may have moved,
    /// an obstacle too).
    Found { len: usize, tested: usize },
}

/// An open weighted A* ([`WEIGHT`]) over the roadmap ([`open`], [`resume`]): what is not
/// in the arena's slots.
#[derive(Clone, Debug)]
pub(crate) struct Search {
    start: Point,
    goal: Point,
    /// The root's and the goal's candidates ([`attach`]): a candidate whose segment to its
    /// end is found blocked is dropped.
    starts: Candidates,
    ends: Candidates,
    /// How far each end's candidates reach, for [`widen`].
    reach: (Reach, Reach),
    /// The root's candidates were tested and the open set holds those it sees.
    ready: bool,
    /// The open set's size (its heap is `Scratch::heap`'s first entries).
    open: usize,
    /// The best way to the goal so far: its length and its last roadmap node.
    best: (f32, u16),
}

/// What a search's call ended with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Poll {
    /// The call's time ran out first: take it up again.
    Pending,
    /// A path of this many nodes ([`resume`]).
    Found(usize),
    /// The roadmap has no way.
    NoPath,
}

/// Whether the scratch has a slot per roadmap node.
fn fits(rm: &Roadmap<'_>, s: &Scratch<'_>) -> bool {
    let n = rm.len();
    n > 0 && s.g.len() >= n && s.parent.len() >= n && s.heap.len() >= n && s.slot.len() >= n
}

/// Opens the weighted A* ([`WEIGHT`]) over the roadmap from `start` (the forward tree's root)
/// to `goal`, in the arena slots `s` (at least [`Roadmap::len`] entries each): finds each
/// end's candidates ([`attach`]); `None` when either end has none. No segment is tested
/// here ([`resume`] tests them).
#[inline(never)]
pub(crate) fn open<C: Clock + ?Sized>(
    rm: &Roadmap<'_>,
    (start, goal): (Point, Point),
    s: &mut Scratch<'_>,
    meter: &Meter<'_, C>,
) -> Option<Search> {
    if !fits(rm, s) {
        return None;
    }
    let new = Reach {
        beyond: (-1.0, 0),
        widened: 0,
    };
    let mut reach = (new, new);
    let ends = attach(rm, goal, &mut reach.1, meter);
    let starts = attach(rm, start, &mut reach.0, meter);
    if ends.is_empty() || starts.is_empty() {
        return None;
    }
    Some(Search {
        start,
        goal,
        starts,
        ends,
        reach,
        ready: false,
        open: 0,
        best: (f32::INFINITY, u16::MAX),
    })
}

impl Search {
    /// Empties the scratch and opens the root's candidates (each a distinct node).
    fn open_starts<C: Clock + ?Sized>(
        &mut self,
        rm: &Roadmap<'_>,
        s: &mut Scratch<'_>,
        meter: &Meter<'_, C>,
    ) {
        let n = rm.len();
        for i in 0..n {
            wr(s.g, i, UNSEEN);
            wr(s.slot, i, 0);
        }
        meter.charge(units(n >> 3).saturating_add(1));
        let goal = self.goal;
        let h = |p: Point| WEIGHT * p.dist(goal);
        self.open = 0;
        self.best = (f32::INFINITY, u16::MAX);
        for &(i, d, _) in &self.starts {
            let iu = usize::from(i);
            let Some(p) = rm.node(iu) else { continue };
            wr(s.g, iu, Point::new(d, d + h(p)));
            wr(s.parent, iu, u16::MAX);
            let at = self.open;
            wr(s.heap, at, i);
            wr(s.slot, iu, slot_of(at));
            self.open = at.saturating_add(1);
            s.sift(at, self.open);
        }
    }

    /// The best way over the goal's candidates whose node is closed (its distance final).
    fn rebest(&mut self, s: &Scratch<'_>) {
        self.best = (f32::INFINITY, u16::MAX);
        for &(e, d, _) in &self.ends {
            if rd(s.slot, usize::from(e), 0) == CLOSED {
                let via = s.dist(usize::from(e)) + d;
                if via < self.best.0 {
                    self.best = (via, e);
                }
            }
        }
    }
}

/// Tests the segment from end `p` to its candidate `node` unless it was seen before; a
/// blocked candidate is dropped from `list`. Returns whether it is free.
fn sees<M: Metric, C: Clock + ?Sized, const K: usize>(
    rm: &Roadmap<'_>,
    env: &Env<'_, '_, M, K>,
    p: Point,
    node: u16,
    list: &mut Candidates,
    meter: &Meter<'_, C>,
) -> bool {
    let Some(c) = list.iter_mut().find(|c| c.0 == node) else {
        return false;
    };
    if c.2 {
        return true;
    }
    c.2 = rm
        .node(usize::from(node))
        .is_some_and(|n| env.free(p, n, meter));
    let free = c.2;
    if !free {
        list.retain(|c| c.0 != node);
    }
    free
}

/// Runs an open search on until it ends or the call's time runs out ([`Poll::Pending`]: the
/// scratch `s` must be handed back unchanged to the next call's). The root's candidates are
/// tested first, [`ATTACH`] kept of those it sees; when the search settles on a way, the
/// segment from the goal to the way's last node is tested (each candidate once): a goal's
/// candidate the goal does not see is dropped and the search goes on. On
/// success returns the path's length `L` in nodes and leaves them at the end of `s.heap`, the
/// `k`-th from the goal's end at `s.heap[len - 1 - k]` (the arena's last slots: the planner
/// reads them back there with `Tree::spare_from_end` while it fills the first ones), each
/// consecutive pair an edge of the roadmap, the first seen from the goal and the last from the
/// root over free segments (the edges between them are not tested here). A path of any length
/// fits: the heap is no longer needed and has a slot per roadmap node. Bounded: each node is
/// closed once, and the search stops at the call's deadline.
#[inline(never)]
pub(crate) fn resume<M: Metric, C: Clock + ?Sized, const K: usize>(
    rm: &Roadmap<'_>,
    env: &Env<'_, '_, M, K>,
    search: &mut Search,
    s: &mut Scratch<'_>,
    meter: &Meter<'_, C>,
) -> Poll {
    if !fits(rm, s) {
        return Poll::NoPath;
    }
    let n = rm.len();
    let goal = search.goal;
    let h = |p: Point| WEIGHT * p.dist(goal);
    if !search.ready {
        // The root's candidates, nearest first, each tested once, until [`ATTACH`] are seen:
        // a root's node found blocked later would cost the search a new start.
        // When it sees none, the next nearest are taken ([`widen`]).
        let start = search.start;
        let mut k = 0usize;
        loop {
            let Some(&(node, _, _)) = search.starts.get(k) else {
                if widen(rm, start, &mut search.starts, &mut search.reach.0, meter) {
                    continue;
                }
                break;
            };
            if k >= ATTACH {
                search.starts.truncate(ATTACH);
                break;
            }
            if meter.expired(&env.call) {
                return Poll::Pending;
            }
            if sees(rm, env, start, node, &mut search.starts, meter) {
                k = k.saturating_add(1);
            }
        }
        if search.starts.is_empty() {
            return Poll::NoPath;
        }
        search.open_starts(rm, s, meter);
        search.ready = true;
    }
    loop {
        while search.open > 0 {
            if meter.expired(&env.call) {
                return Poll::Pending;
            }
            let i = rd(s.heap, 0, 0);
            if s.key(i) >= search.best.0 {
                break;
            }
            // Pop the top.
            search.open = search.open.saturating_sub(1);
            let len = search.open;
            s.swap(0, len);
            wr(s.slot, usize::from(i), CLOSED);
            s.sift(0, len);
            let iu = usize::from(i);
            let gi = s.dist(iu);
            if let Some(&(_, d, _)) = search.ends.iter().find(|c| c.0 == i)
                && gi + d < search.best.0
            {
                search.best = (gi + d, i);
            }
            let Some(pi) = rm.node(iu) else { continue };
            let mut work = 2u32;
            for j in rm.neighbours(iu) {
                work = work.saturating_add(1);
                let Ok(ju) = u16::try_from(j) else { continue };
                let sj = rd(s.slot, j, CLOSED);
                if sj == CLOSED {
                    continue;
                }
                // Only a shorter way counts: skip the square root when the squares tell.
                let gj = s.dist(j);
                if gj <= gi {
                    continue;
                }
                let Some(pj) = rm.node(j) else { continue };
                let d2 = pi.dist_sq(pj);
                if gj.is_finite() && d2 >= (gj - gi) * (gj - gi) {
                    continue;
                }
                let nd = gi + crate::geometry::sqrt(d2);
                if nd < gj {
                    wr(s.g, j, Point::new(nd, nd + h(pj)));
                    wr(s.parent, j, i);
                    if sj == 0 {
                        let at = search.open;
                        wr(s.heap, at, ju);
                        wr(s.slot, j, slot_of(at));
                        search.open = at.saturating_add(1);
                        s.sift(at, search.open);
                    } else {
                        s.sift(usize::from(sj).saturating_sub(1), search.open);
                    }
                }
            }
            meter.charge(work);
        }
        let last = search.best.1;
        if last == u16::MAX {
            // Every node the root reaches is closed and none is a goal's candidate (they lie
            // in another part of the roadmap, behind a wall): the next nearest ([`widen`]).
            search.ends.clear();
            if widen(rm, goal, &mut search.ends, &mut search.reach.1, meter) {
                search.rebest(s);
                continue;
            }
            return Poll::NoPath;
        }
        // The goal's segment to the way's last node, each candidate tested once (the root's
        // were tested before the search opened).
        if sees(rm, env, goal, last, &mut search.ends, meter) {
            break;
        }
        // The goal sees none of its candidates: the next nearest ([`widen`]); those the
        // search has closed count at once.
        widen(rm, goal, &mut search.ends, &mut search.reach.1, meter);
        search.rebest(s);
        if meter.expired(&env.call) {
            return Poll::Pending;
        }
    }
    search.open = 0;
    // The chain of parents, written from the heap's last slot down (at most `n` nodes: each
    // node has one parent, set when it was opened, and the root's candidates none).
    let end = s.heap.len();
    let mut at = search.best.1;
    let mut len = 0usize;
    while at != u16::MAX {
        if len >= n || len >= end {
            return Poll::NoPath;
        }
        wr(s.heap, end.saturating_sub(1).saturating_sub(len), at);
        len = len.saturating_add(1);
        at = rd(s.parent, usize::from(at), u16::MAX);
    }
    Poll::Found(len)
}

#[cfg(test)]
mod tests;
