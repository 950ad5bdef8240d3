//! Dynamic obstacles (paper, section 3: circles; beyond it, moving ones with the capsules
//! they sweep).

use crate::error::ObstacleError;
use crate::geometry::{Point, segment_point_dist_sq, segment_segment_dist_sq};

/// A closed disc: a dynamic obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Circle {
    /// Centre in metres.
    pub center: Point,
    /// Radius in metres.
    pub radius: f32,
}

impl Circle {
    /// A disc of `radius` around `center`.
    pub const fn new(center: Point, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Whether `p` lies in the closed disc.
    pub fn contains(&self, p: Point) -> bool {
        p.dist_sq(self.center) <= self.radius * self.radius
    }

    /// Whether the closed segment `a-b` meets the closed disc (distance from the centre to the
    /// segment at most the radius).
    pub fn intersects_segment(&self, a: Point, b: Point) -> bool {
        segment_point_dist_sq(a, b, self.center) <= self.radius * self.radius
    }

    fn is_valid(&self) -> bool {
        self.center.is_finite() && self.radius.is_finite() && self.radius > 0.0
    }
}

/// A dynamic obstacle as a perception stack reports it (beyond the paper: its obstacles stay
/// put): a disc where it is at the next `plan` call, its velocity, and how long that
/// prediction may be trusted. A still circle is `Moving::still(circle)`.
///
/// Over a time window `[0, w]` the obstacle sweeps the capsule from `center` to
/// `center + velocity * min(w, trusted_for)` of radius `radius + bound * max(0, w -
/// trusted_for)`, where `bound` is the stated top speed of any obstacle
/// ([`crate::config::Motion::obstacle_speed`]): past its horizon the obstacle may have turned
/// anywhere at that speed ([`Moving::sweep`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Moving {
    /// The disc at the time of the next `plan` call.
    pub circle: Circle,
    /// Velocity in metres per second.
    pub velocity: Point,
    /// Seconds for which the straight-line prediction holds (`f32::INFINITY`: for ever).
    pub trusted_for: f32,
}

impl Moving {
    /// A circle that does not move.
    pub const fn still(circle: Circle) -> Self {
        Self {
            circle,
            velocity: Point::ZERO,
            trusted_for: f32::INFINITY,
        }
    }

    /// A circle moving at `velocity` (m/s), trusted for ever.
    pub const fn new(circle: Circle, velocity: Point) -> Self {
        Self {
            circle,
            velocity,
            trusted_for: f32::INFINITY,
        }
    }

    /// The same, its prediction trusted for `seconds` only.
    pub const fn trusted_for(mut self, seconds: f32) -> Self {
        self.trusted_for = seconds;
        self
    }

    /// The capsule swept over `[0, window]` seconds by an obstacle whose speed is at most
    /// `bound` once its prediction ends: `(from, to, radius)`.
    pub fn sweep(&self, window: f32, bound: f32) -> (Point, Point, f32) {
        let c = self.circle.center;
        let trusted = window.min(self.trusted_for).max(0.0);
        let beyond = (window - self.trusted_for).max(0.0);
        let to = Point::new(
            c.x + self.velocity.x * trusted,
            c.y + self.velocity.y * trusted,
        );
        (c, to, self.circle.radius + bound * beyond)
    }

    /// Whether the closed segment `a-b` meets the capsule swept over `[0, window]`.
    pub fn sweep_meets(&self, a: Point, b: Point, window: f32, bound: f32) -> bool {
        let (from, to, r) = self.sweep(window, bound);
        if from == to {
            segment_point_dist_sq(a, b, from) <= r * r
        } else {
            segment_segment_dist_sq(a, b, from, to) <= r * r
        }
    }

    fn is_valid(&self) -> bool {
        self.circle.is_valid() && self.velocity.is_finite() && self.trusted_for >= 0.0
    }
}

/// Identifies a dynamic obstacle for its removal. Ids are not reused until 2^32 further
/// additions have been made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ObstacleId(pub u32);

/// A bounded set of at most `K` dynamic obstacles, still or moving.
///
/// Two tests: *now* ([`Obstacles::blocks_now`], [`Obstacles::contains_now`]) against the
/// discs where they are, and the *tree's* ([`Obstacles::blocks_segment`],
/// [`Obstacles::contains`]) against what each sweeps over the edge window
/// ([`Obstacles::set_sweep`]: the planner sets it to [`crate::config::Motion::horizon`]): a
/// tree edge is judged against where its obstacles will be within that window, so the path
/// passes behind a walking person rather than in front. With still circles, or a window of 0,
/// both tests are the paper's.
#[derive(Clone, Debug)]
pub struct Obstacles<const K: usize> {
    items: heapless::Vec<(ObstacleId, Moving), K>,
    next_id: u32,
    /// Edge window in seconds and the obstacles' top speed past a prediction, in m/s.
    window: f32,
    bound: f32,
    /// The robot's radius: every disc is kept grown by it ([`Obstacles::set_pad`]).
    pad: f32,
}

impl<const K: usize> Default for Obstacles<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> Obstacles<K> {
    /// An empty set.
    pub const fn new() -> Self {
        Self {
            items: heapless::Vec::new(),
            next_id: 0,
            window: 0.0,
            bound: 0.0,
            pad: 0.0,
        }
    }

    /// Grows every disc, present and to come, by the robot's `radius` (a circle of radius R
    /// then blocks R + r: the tests below are the robot disc's). The planner sets it from its
    /// map's body ([`Map::radius`](crate::map::Map::radius)); non-finite or negative values count as 0. What
    /// [`Obstacles::get`], [`Obstacles::iter`] and [`Obstacles::remove`] return is the disc as
    /// given; [`Obstacles::as_slice`] holds the grown ones.
    pub fn set_pad(&mut self, radius: f32) {
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            0.0
        };
        let delta = radius - self.pad;
        for (_, m) in self.items.iter_mut() {
            m.circle.radius += delta;
        }
        self.pad = radius;
    }

    /// The robot's radius the discs are grown by.
    pub fn pad(&self) -> f32 {
        self.pad
    }

    /// `obstacle` grown by the pad.
    fn padded(&self, mut obstacle: Moving) -> Moving {
        obstacle.circle.radius += self.pad;
        obstacle
    }

    /// A grown disc as given.
    fn unpadded(&self, mut circle: Circle) -> Circle {
        circle.radius -= self.pad;
        circle
    }

    /// Sets the tree's edge window (seconds) and the obstacles' top speed past a prediction
    /// (m/s); non-finite or negative values count as 0.
    pub fn set_sweep(&mut self, window: f32, bound: f32) {
        let ok = |v: f32| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        self.window = ok(window);
        self.bound = ok(bound);
    }

    /// The edge window and top speed ([`Obstacles::set_sweep`]).
    pub fn sweep(&self) -> (f32, f32) {
        (self.window, self.bound)
    }

    /// Adds a still circle and returns its id; `Err(Full)` when `K` circles are present,
    /// `Err(BadCircle)` for a non-finite centre or a radius that is not finite and positive.
    pub fn add(&mut self, circle: Circle) -> Result<ObstacleId, ObstacleError> {
        self.add_moving(Moving::still(circle))
    }

    /// Adds an obstacle that may move; `Err(BadCircle)` also for a non-finite velocity or a
    /// horizon that is negative or NaN.
    pub fn add_moving(&mut self, obstacle: Moving) -> Result<ObstacleId, ObstacleError> {
        if !obstacle.is_valid() {
            return Err(ObstacleError::BadCircle);
        }
        if self.items.is_full() {
            return Err(ObstacleError::Full);
        }
        // Skip ids still in use after a wrap-around (at most K of them).
        let mut id = ObstacleId(self.next_id);
        while self.get(id).is_some() {
            id = ObstacleId(id.0.wrapping_add(1));
        }
        self.next_id = id.0.wrapping_add(1);
        let obstacle = self.padded(obstacle);
        self.items
            .push((id, obstacle))
            .map_err(|_| ObstacleError::Full)?;
        Ok(id)
    }

    /// Replaces what is known of an obstacle (a new position, velocity or horizon): O(K).
    pub fn update(&mut self, id: ObstacleId, obstacle: Moving) -> Result<(), ObstacleError> {
        if !obstacle.is_valid() {
            return Err(ObstacleError::BadCircle);
        }
        let obstacle = self.padded(obstacle);
        let slot = self
            .items
            .iter_mut()
            .find(|(i, _)| *i == id)
            .ok_or(ObstacleError::UnknownId)?;
        slot.1 = obstacle;
        Ok(())
    }

    /// Removes the obstacle with this id and returns its disc.
    pub fn remove(&mut self, id: ObstacleId) -> Result<Circle, ObstacleError> {
        let pos = self
            .items
            .iter()
            .position(|(i, _)| *i == id)
            .ok_or(ObstacleError::UnknownId)?;
        let circle = self.items.swap_remove(pos).1.circle;
        Ok(self.unpadded(circle))
    }

    /// The disc of the obstacle with this id (as given, not grown by the pad).
    pub fn get(&self, id: ObstacleId) -> Option<Circle> {
        self.get_moving(id).map(|m| m.circle)
    }

    /// What is known of the obstacle with this id (its disc as given).
    pub fn get_moving(&self, id: ObstacleId) -> Option<Moving> {
        self.items
            .iter()
            .find(|(i, _)| *i == id)
            .map(|(_, m)| Moving {
                circle: self.unpadded(m.circle),
                ..*m
            })
    }

    /// The discs present with their ids (as given), in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = (ObstacleId, Circle)> + '_ {
        self.items
            .iter()
            .map(|(i, m)| (*i, self.unpadded(m.circle)))
    }

    /// The obstacles present with their ids and motion, as a slice (discs grown by the pad).
    pub fn as_slice(&self) -> &[(ObstacleId, Moving)] {
        &self.items
    }

    /// Number of obstacles present.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no obstacle is present.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Removes every obstacle.
    pub fn clear(&mut self) {
        self.items.clear();
    }

    /// The tree's test: whether any obstacle's sweep over the edge window meets `a-b` (the
    /// disc itself when still or with a window of 0).
    pub fn blocks_segment(&self, a: Point, b: Point) -> bool {
        self.blocks_within(a, b, self.window)
    }

    /// Whether any obstacle's sweep over `[0, window]` seconds meets `a-b`.
    #[inline(never)]
    pub fn blocks_within(&self, a: Point, b: Point, window: f32) -> bool {
        !self.items.is_empty() && sweeps_meet(&self.items, a, b, window, self.bound)
    }

    /// The tree's test: whether any obstacle's sweep over the edge window contains `p`.
    pub fn contains(&self, p: Point) -> bool {
        self.blocks_segment(p, p)
    }

    /// Whether any disc, where it is now, meets `a-b`.
    pub fn blocks_now(&self, a: Point, b: Point) -> bool {
        discs_meet(&self.items, a, b)
    }

    /// Whether any disc, where it is now, contains `p`.
    pub fn contains_now(&self, p: Point) -> bool {
        self.items.iter().any(|(_, m)| m.circle.contains(p))
    }
}

/// Whether any of `items` sweeps `a-b` over `[0, window]` (one copy for every capacity `K`;
/// also the waypoint rule's, module `motion`).
#[inline(never)]
pub(crate) fn sweeps_meet(
    items: &[(ObstacleId, Moving)],
    a: Point,
    b: Point,
    window: f32,
    bound: f32,
) -> bool {
    items
        .iter()
        .any(|(_, m)| m.sweep_meets(a, b, window, bound))
}

/// Whether any of `items`' discs, where they are now, meets `a-b`.
pub(crate) fn discs_meet(items: &[(ObstacleId, Moving)], a: Point, b: Point) -> bool {
    items.iter().any(|(_, m)| m.circle.intersects_segment(a, b))
}
