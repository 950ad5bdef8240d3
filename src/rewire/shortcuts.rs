//! Path shortcuts and corner cuts (tuned; not in the paper: Theta*'s any-angle step, Nash et
//! al. 2007): the module's "Path shortcuts".

use super::*;

/// Segment tests of one corner cut's bisection ([`TreeStore::cut_corner`]), after a first
/// test 1/32 of the way along the parent's edge: the cut point lies within 1/256 of the
/// edge of the farthest point seen.
const CUT_STEPS: usize = 5;

/// A corner cut's first test reaches `1 / FIRST_PROBE_DIV` of the way along the edge.
const FIRST_PROBE_DIV: f32 = 32.0;

/// A corner cut is kept when it shortens the path by this share of a cell at least. A tenth
/// until issue 42 left up to a tenth of a cell at each corner of the path (cost at 1 s 1.002-
/// 1.004 x the optimum on several reference legs, where Informed RRT* reached 1.0002-1.0007);
/// at 1/200 the residue is a few millimetres a corner on metre cells, with no fewer
/// expansions a second (docs/notebook/tuned-default.md, "Corner cuts").
const CUT_GAIN: f32 = 0.005;

/// The largest `d` in `(0, reach]` at which `sees(d)` holds, by bisection from `reach / 32`
/// ([`CUT_STEPS`] more tests), for the corner cuts; `None` when the first test fails or the
/// call's deadline passes.
fn farthest_seen<M: Metric, C: Clock + ?Sized, const K: usize>(
    env: &Env<'_, '_, M, K>,
    meter: &Meter<'_, C>,
    reach: f32,
    mut sees: impl FnMut(f32) -> bool,
) -> Option<f32> {
    let first = reach / FIRST_PROBE_DIV;
    if meter.expired(&env.call) || !sees(first) {
        return None;
    }
    let (mut lo, mut hi) = (first, reach);
    for _ in 0..CUT_STEPS {
        if meter.expired(&env.call) {
            return None;
        }
        let mid = 0.5 * (lo + hi);
        if sees(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

impl<const N: usize, const B: usize> TreeStore<N, B> {
    /// Path shortcuts ([`crate::config::Rewiring::path_shortcuts`], module docs): up to `tests` nodes of the
    /// path to `goal`, from where the last call stopped, each offered its grandparent as
    /// parent (kept while it shortens the path, as Theta* does); back to the goal after the
    /// root.
    pub(crate) fn shortcut_path<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        goal: NodeId,
        tests: u16,
        meter: &Meter<'_, C>,
    ) {
        // A cursor renamed or dropped by recycling names some other node or none: any node
        // may be shortcut, so that only costs a pass.
        let mut x = self
            .shortcut_at
            .filter(|x| x.index() < self.tree.len())
            .unwrap_or(goal);
        for _ in 0..tests {
            // Each test may move a subtree: the call's deadline is checked before each.
            if meter.expired(&env.call) {
                break;
            }
            meter.charge(1);
            let grand = self
                .tree
                .parent(x)
                .and_then(|p| Some((p, self.tree.parent(p)?)));
            let Some((parent, grand)) = grand else {
                x = goal; // the root or its child: a new pass
                continue;
            };
            // The grandparent as parent when that is shorter and `x` sees it; when it is
            // hidden, a corner cut (`corner_cuts`; the cursor goes on from the cut's new node).
            x = match self.rewire(env, grand, x, None, false, meter) {
                Ok(()) => x,
                Err(Refused::Hidden) if env.cfg.tactics.corner_cuts => self
                    .cut_corner(env, x, parent, grand, meter)
                    .unwrap_or(parent),
                Err(_) => parent,
            };
        }
        self.shortcut_at = Some(x);
    }

    /// A corner cut (the `corner_cuts` tactic, module docs): `x` cannot see its
    /// grandparent `g` round its parent `p`. A point `q` of one of the two edges at `p`
    /// becomes a new node below `g` and the parent of `x`: first the farthest point of `p - g`
    /// that `x` sees, else the farthest point of `p - x` that `g` sees (bisection from `p`,
    /// [`CUT_STEPS`] tests). The way `x - q - g` is shorter than `x - p - g` (triangle
    /// inequality: `q` lies on one of the two segments), and cuts from both sides in turn
    /// close in on the corner, as a path simplifier's shortcuts place new vertices on a
    /// path's segments. Kept only when it shortens the path by [`CUT_GAIN`] of a cell; the part of
    /// the old edge that `q` keeps is tested too (a rounded point may leave the line).
    /// Returns the new node.
    fn cut_corner<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        x: NodeId,
        p: NodeId,
        g: NodeId,
        meter: &Meter<'_, C>,
    ) -> Option<NodeId> {
        if self.tree.is_full() || self.cost(x).blocked {
            return None;
        }
        let (px, pp, pg) = (self.pos(x), self.pos(p), self.pos(g));
        // (the eye, the edge's far end): x looking along p - g, then g along p - x.
        let one = [(px, pg), (pg, px)]
            .into_iter()
            .find_map(|(eye, end)| self.cut_point(env, eye, pp, end, meter));
        // Neither end sees past `p`: `p` splits in two, one point on each edge.
        let (a, b) = match one {
            Some(q) => (q, None),
            None => {
                let (a, b) = self.split_points(env, px, pp, pg, meter)?;
                (a, Some(b))
            }
        };
        let last = b.unwrap_or(a);
        // The new edges g - a (- b) - x, each with its clearance class.
        let (e_ga, e_ab, e_x) = (
            env.edge(pg, a, meter),
            b.map(|b| env.edge(a, b, meter)).unwrap_or_default(),
            env.edge(last, px, meter),
        );
        let cost = self
            .cost(g)
            .extend(env.charged(pg.dist(a), e_ga.class), false);
        let cost = b.map_or(cost, |b| {
            cost.extend(env.charged(a.dist(b), e_ab.class), false)
        });
        if cost.extend(env.charged(last.dist(px), e_x.class), false) >= self.cost(x)
            || self.tree.len().saturating_add(2) > N
        {
            return None;
        }
        let cut = self.insert(a, g, e_ga).ok()?;
        let cut = match b {
            Some(b) => self.insert(b, cut, e_ab).ok()?,
            None => cut,
        };
        self.move_below(x, cut, e_x, meter)?;
        Some(cut)
    }

    /// A corner node `p` split in two (the last corner cut, [`TreeStore::cut_corner`]): the
    /// points `a` of `p - g` and `b` of `p - x` at the same distance `d` from `p`, for the
    /// largest `d` (bisection) at which they see each other, when the way `a - b` is shorter
    /// than `a - p - b` by [`CUT_GAIN`] of a cell and the rest of both edges, `a - g` and `b - x`,
    /// is free. The cuts from both sides then pull `a` and `b` round the corner.
    fn split_points<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        px: Point,
        pp: Point,
        pg: Point,
        meter: &Meter<'_, C>,
    ) -> Option<(Point, Point)> {
        let (lg, lx) = (pp.dist(pg), pp.dist(px));
        let reach = lg.min(lx);
        if reach.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        let at = |d: f32| (pp.lerp(pg, d / lg), pp.lerp(px, d / lx));
        let lo = farthest_seen(env, meter, reach, |d| {
            let (a, b) = at(d);
            env.free(a, b, meter)
        })?;
        let (a, b) = at(lo);
        let gain = 2.0 * lo - a.dist(b);
        (gain > CUT_GAIN * env.map.grid().cell_size()
            && env.free(a, pg, meter)
            && env.free(b, px, meter))
        .then_some((a, b))
    }

    /// The farthest point `q` of the free segment `p - end` that `eye` sees, when the way
    /// `eye - q` is shorter than `eye - p - q` by [`CUT_GAIN`] of a cell and `q - end` is free
    /// ([`TreeStore::cut_corner`]). A corner already cut (`eye` sees nothing of the segment
    /// past `p`) costs one test.
    fn cut_point<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        eye: Point,
        p: Point,
        end: Point,
        meter: &Meter<'_, C>,
    ) -> Option<Point> {
        let lo = farthest_seen(env, meter, 1.0, |t| env.free(eye, p.lerp(end, t), meter))?;
        let q = p.lerp(end, lo);
        let gain = eye.dist(p) + p.dist(q) - eye.dist(q);
        (gain > CUT_GAIN * env.map.grid().cell_size() && env.free(q, end, meter)).then_some(q)
    }
}
