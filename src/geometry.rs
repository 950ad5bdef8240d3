//! Plane geometry on `f32`: points, segments and the two sampling shapes the planner draws from.
//!
//! The planner lives in a bounded rectangle of the plane (paper, section 3: the state space is
//! the map). Everything here is plain `f32` arithmetic plus `libm` for the few transcendental
//! functions, so the host and a Cortex-M4F compute bit-identical results.
//!
//! Sampling: a uniform point in a disc (stochastic steering, paper Algorithm 2) and a uniform
//! point in the informed ellipse whose foci are the root and the goal and whose major axis is the
//! current best cost (Gammell et al.'s informed sampling, used by AM-RRT* and Bi-AM-RRT*).

// `Point` operators are f32 maths (never a panic); the integer-overflow lint cannot tell.
#![allow(clippy::arithmetic_side_effects)]

use core::ops::{Add, Mul, Sub};

use rand_core::Rng;

/// The square root every distance goes through. IEEE 754 requires it correctly rounded, and
/// both routes are: `libm`'s software routine (the default, stable Rust) and, with the
/// feature `hw-sqrt` (nightly Rust: `core::f32::math` is unstable), the target's own (the
/// Cortex-M4F's `vsqrt.f32`, 14 cycles; where a target has none, the compiler calls a
/// software one). Same bits either way, so host and MCU still agree bit for bit: the host's
/// `libm` uses the SSE instruction, the stable firmware the software routine, the `hw-sqrt`
/// firmware `vsqrt.f32`, and all three print the same twin line (CI compares them).
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(feature = "hw-sqrt")]
    {
        core::f32::math::sqrt(x)
    }
    #[cfg(not(feature = "hw-sqrt"))]
    {
        libm::sqrtf(x)
    }
}

/// A point (or vector) of the plane, in metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Point {
    /// Horizontal coordinate (map column direction).
    pub x: f32,
    /// Vertical coordinate (map row direction).
    pub y: f32,
}

impl Point {
    /// The origin.
    pub const ZERO: Point = Point { x: 0.0, y: 0.0 };

    /// A point from its coordinates.
    #[inline]
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// Both coordinates are finite (neither NaN nor infinite).
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// Dot product.
    #[inline]
    pub fn dot(self, o: Point) -> f32 {
        self.x * o.x + self.y * o.y
    }

    /// Squared Euclidean norm.
    #[inline]
    pub fn norm_sq(self) -> f32 {
        self.dot(self)
    }

    /// Euclidean norm.
    #[inline]
    pub fn norm(self) -> f32 {
        sqrt(self.norm_sq())
    }

    /// Squared Euclidean distance to `o`.
    #[inline]
    pub fn dist_sq(self, o: Point) -> f32 {
        (self - o).norm_sq()
    }

    /// Euclidean distance to `o` (`d_E` in the paper).
    #[inline]
    pub fn dist(self, o: Point) -> f32 {
        sqrt(self.dist_sq(o))
    }

    /// The point at fraction `t` of the way from `self` to `o` (`t = 0` gives `self`).
    #[inline]
    pub fn lerp(self, o: Point, t: f32) -> Point {
        Point::new(self.x + (o.x - self.x) * t, self.y + (o.y - self.y) * t)
    }

    /// The point at most `max_len` from `self` along the segment towards `o` (the RRT "steer").
    /// Returns `o` itself when it is that close already.
    #[inline]
    pub fn step_towards(self, o: Point, max_len: f32) -> Point {
        let d = self.dist(o);
        if d <= max_len || d == 0.0 {
            o
        } else {
            self.lerp(o, max_len / d)
        }
    }
}

impl Add for Point {
    type Output = Point;
    #[inline]
    fn add(self, o: Point) -> Point {
        Point::new(self.x + o.x, self.y + o.y)
    }
}

impl Sub for Point {
    type Output = Point;
    #[inline]
    fn sub(self, o: Point) -> Point {
        Point::new(self.x - o.x, self.y - o.y)
    }
}

impl Mul<f32> for Point {
    type Output = Point;
    #[inline]
    fn mul(self, k: f32) -> Point {
        Point::new(self.x * k, self.y * k)
    }
}

/// Parameter in `[0, 1]` of the point of segment `a-b` closest to `p`.
#[inline]
pub fn closest_param(a: Point, b: Point, p: Point) -> f32 {
    let ab = b - a;
    let len_sq = ab.norm_sq();
    if len_sq == 0.0 {
        return 0.0;
    }
    ((p - a).dot(ab) / len_sq).clamp(0.0, 1.0)
}

/// Squared distance from `p` to the closed segment `a-b` (not to the infinite line).
#[inline]
pub fn segment_point_dist_sq(a: Point, b: Point, p: Point) -> f32 {
    a.lerp(b, closest_param(a, b, p)).dist_sq(p)
}

/// Squared distance between the closed segments `a-b` and `c-d` (the closest points of the
/// two, clamped to the segments: Ericson, *Real-Time Collision Detection*, 5.1.9).
pub fn segment_segment_dist_sq(a: Point, b: Point, c: Point, d: Point) -> f32 {
    let (d1, d2, r) = (b - a, d - c, a - c);
    let (aa, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let unit = |v: f32| v.clamp(0.0, 1.0);
    let (s, t) = if aa == 0.0 && e == 0.0 {
        (0.0, 0.0)
    } else if aa == 0.0 {
        (0.0, unit(f / e))
    } else {
        let cc = d1.dot(r);
        if e == 0.0 {
            (unit(-cc / aa), 0.0)
        } else {
            let bb = d1.dot(d2);
            let denom = aa * e - bb * bb;
            let s = if denom > 0.0 {
                unit((bb * f - cc * e) / denom)
            } else {
                0.0
            };
            let t = (bb * s + f) / e;
            if t < 0.0 {
                (unit(-cc / aa), 0.0)
            } else if t > 1.0 {
                (unit((bb - cc) / aa), 1.0)
            } else {
                (s, t)
            }
        }
    };
    a.lerp(b, s).dist_sq(c.lerp(d, t))
}

/// A uniform `f32` in `[0, 1)` from 24 random bits.
#[inline]
pub fn unit_f32<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    // 24 bits fill an f32 mantissa exactly, so every value is representable and < 1.
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A uniform point in the disc of radius `radius` around `center`.
pub fn sample_disc<R: Rng + ?Sized>(rng: &mut R, center: Point, radius: f32) -> Point {
    center + sample_unit_disc(rng) * radius
}

/// A uniform point in the unit disc (polar method with the square-root radius law).
pub fn sample_unit_disc<R: Rng + ?Sized>(rng: &mut R) -> Point {
    let r = sqrt(unit_f32(rng));
    let theta = unit_f32(rng) * core::f32::consts::TAU;
    // One range reduction for both: the same bits as `cosf` and `sinf` (unit test), a quarter
    // of their time.
    let (sin, cos) = libm::sincosf(theta);
    Point::new(r * cos, r * sin)
}

/// `n` states in the disc of radius `radius` around `center`, spread evenly in angle: a
/// uniform random first direction, then equal turns of `2 pi / n`, each at a radius drawn with
/// the square-root law. Each state alone is uniform in the disc (as [`sample_disc`]), and
/// together they cover every direction, so fewer of them find the way around an obstacle; one
/// sine-cosine for the whole fan instead of one per state.
#[derive(Clone, Copy, Debug)]
pub struct DiscFan {
    center: Point,
    radius: f32,
    dir: Point,
    turn: Point,
}

impl DiscFan {
    /// A fan of `n` (at least 1) states around `center`; draws the first direction.
    pub fn new<R: Rng + ?Sized>(rng: &mut R, center: Point, radius: f32, n: u16) -> Self {
        let theta = unit_f32(rng) * core::f32::consts::TAU;
        let (sin, cos) = libm::sincosf(theta);
        let (turn_sin, turn_cos) = libm::sincosf(core::f32::consts::TAU / f32::from(n.max(1)));
        Self {
            center,
            radius,
            dir: Point::new(cos, sin),
            turn: Point::new(turn_cos, turn_sin),
        }
    }

    /// The next state of the fan (its radius drawn now).
    pub fn next_state<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Point {
        let r = sqrt(unit_f32(rng)) * self.radius;
        let p = self.center + self.dir * r;
        let (d, t) = (self.dir, self.turn);
        self.dir = Point::new(d.x * t.x - d.y * t.y, d.x * t.y + d.y * t.x);
        p
    }
}

/// The informed ellipse: all points whose summed distance to two foci is at most `c_best`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ellipse {
    center: Point,
    /// Unit vector along the major axis (from focus `f1` to focus `f2`).
    axis: Point,
    /// Semi-major axis.
    a: f32,
    /// Semi-minor axis.
    b: f32,
}

impl Ellipse {
    /// The ellipse with foci `f1`, `f2` and transverse diameter `c_best` (the length of the best
    /// path found so far). `None` when `c_best` is not finite or shorter than the focal distance
    /// (no point can then improve the path, or the foci coincide with a zero diameter).
    pub fn new(f1: Point, f2: Point, c_best: f32) -> Option<Self> {
        let c_min = f1.dist(f2);
        if !c_best.is_finite() || !c_min.is_finite() || c_best < c_min || c_best <= 0.0 {
            return None;
        }
        let axis = if c_min > 0.0 {
            (f2 - f1) * (1.0 / c_min)
        } else {
            Point::new(1.0, 0.0)
        };
        let a = 0.5 * c_best;
        let b = 0.5 * sqrt(c_best * c_best - c_min * c_min);
        Some(Self {
            center: f1.lerp(f2, 0.5),
            axis,
            a,
            b,
        })
    }

    /// Whether `p` lies inside or on the ellipse.
    pub fn contains(&self, p: Point) -> bool {
        let d = p - self.center;
        let u = d.dot(self.axis);
        let v = d.x * -self.axis.y + d.y * self.axis.x;
        if self.b == 0.0 {
            // Degenerate: the segment between the foci.
            return libm::fabsf(v) <= f32::EPSILON * self.a && libm::fabsf(u) <= self.a;
        }
        (u / self.a) * (u / self.a) + (v / self.b) * (v / self.b) <= 1.0
    }

    /// Semi-major and semi-minor axes.
    pub fn axes(&self) -> (f32, f32) {
        (self.a, self.b)
    }

    /// A uniform point inside the ellipse: a uniform point of the unit disc stretched by the
    /// axes, rotated onto the focal axis and moved to the centre.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Point {
        let q = sample_unit_disc(rng);
        let (u, v) = (q.x * self.a, q.y * self.b);
        Point::new(
            self.center.x + u * self.axis.x - v * self.axis.y,
            self.center.y + u * self.axis.y + v * self.axis.x,
        )
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn segment_distance_matches_sampling() {
        use super::{Point, segment_point_dist_sq, segment_segment_dist_sq};
        let pts = [
            (
                Point::new(0.0, 0.0),
                Point::new(4.0, 0.0),
                Point::new(2.0, -1.0),
                Point::new(2.0, 3.0),
            ),
            (
                Point::new(0.0, 0.0),
                Point::new(4.0, 0.0),
                Point::new(5.0, 1.0),
                Point::new(7.0, 3.0),
            ),
            (
                Point::new(0.0, 0.0),
                Point::new(4.0, 0.0),
                Point::new(1.0, 2.0),
                Point::new(3.0, 2.0),
            ),
            (
                Point::new(1.0, 1.0),
                Point::new(1.0, 1.0),
                Point::new(0.0, 0.0),
                Point::new(2.0, 0.0),
            ),
            (
                Point::new(1.0, 1.0),
                Point::new(1.0, 1.0),
                Point::new(3.0, 4.0),
                Point::new(3.0, 4.0),
            ),
            (
                Point::new(0.0, 0.0),
                Point::new(2.0, 2.0),
                Point::new(2.0, 0.0),
                Point::new(4.0, 2.0),
            ),
            (
                Point::new(-3.0, 1.0),
                Point::new(-1.0, 0.5),
                Point::new(0.0, -2.0),
                Point::new(0.5, 4.0),
            ),
        ];
        for (a, b, c, d) in pts {
            // Brute force: the least distance from 2,001 points of one to the other.
            let brute = (0..=2000)
                .map(|i| segment_point_dist_sq(c, d, a.lerp(b, i as f32 / 2000.0)))
                .fold(f32::INFINITY, f32::min);
            let got = segment_segment_dist_sq(a, b, c, d);
            assert!(
                (got.sqrt() - brute.sqrt()).abs() < 2e-3,
                "{a:?} {b:?} {c:?} {d:?}: {got} vs {brute}"
            );
        }
    }

    use super::*;

    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn segment_distance_uses_the_segment_not_the_line() {
        let (a, b) = (Point::new(0.0, 0.0), Point::new(1.0, 0.0));
        assert_eq!(segment_point_dist_sq(a, b, Point::new(0.5, 2.0)), 4.0);
        // Beyond the end: distance to the endpoint, not to the line (which would be 0).
        assert_eq!(segment_point_dist_sq(a, b, Point::new(3.0, 0.0)), 4.0);
        assert_eq!(segment_point_dist_sq(a, a, Point::new(3.0, 4.0)), 25.0);
    }

    #[test]
    fn sincos_is_bit_identical_to_sin_and_cos_on_every_sampled_angle() {
        // Every angle `sample_unit_disc` can draw: the 2^24 values of `unit_f32` times TAU.
        for i in 0u32..1 << 24 {
            let theta = i as f32 * (1.0 / 16_777_216.0) * core::f32::consts::TAU;
            let (s, c) = libm::sincosf(theta);
            assert_eq!(s.to_bits(), libm::sinf(theta).to_bits(), "sin {theta}");
            assert_eq!(c.to_bits(), libm::cosf(theta).to_bits(), "cos {theta}");
        }
    }

    #[test]
    fn step_towards_is_bounded() {
        let a = Point::new(1.0, 1.0);
        let b = Point::new(11.0, 1.0);
        assert_eq!(a.step_towards(b, 5.0), Point::new(6.0, 1.0));
        assert_eq!(a.step_towards(b, 50.0), b);
        assert_eq!(a.step_towards(a, 5.0), a);
    }

    #[test]
    fn disc_samples_are_inside_and_spread() {
        let mut rng = XorShiftRng::seed_from_u64(7);
        let c = Point::new(3.0, -2.0);
        let mut inner = 0;
        for _ in 0..20_000 {
            let p = sample_disc(&mut rng, c, 2.0);
            assert!(p.dist(c) <= 2.0 + 1e-5);
            if p.dist(c) < 1.0 {
                inner += 1;
            }
        }
        // Uniform in area: a quarter of the samples within half the radius.
        assert!((4_500..5_500).contains(&inner), "{inner}");
    }

    #[test]
    fn a_fan_covers_every_direction_and_each_state_is_uniform() {
        let mut rng = XorShiftRng::seed_from_u64(9);
        let c = Point::new(3.0, -2.0);
        let (mut inner, mut sector) = (0, [0u32; 8]);
        for _ in 0..2_000 {
            let mut fan = DiscFan::new(&mut rng, c, 2.0, 16);
            let mut angles = [0.0f32; 16];
            for a in angles.iter_mut() {
                let p = fan.next_state(&mut rng);
                let d = p.dist(c);
                assert!(d <= 2.0 + 1e-5);
                if d < 1.0 {
                    inner += 1;
                }
                *a = libm::atan2f(p.y - c.y, p.x - c.x);
                let s = ((*a + core::f32::consts::PI) / core::f32::consts::TAU * 8.0) as usize;
                sector[s.min(7)] += 1;
            }
            // Successive states turn by 2 pi / 16 (the equal turns of the fan).
            for w in angles.windows(2) {
                let turn = (w[1] - w[0]).rem_euclid(core::f32::consts::TAU);
                assert!(
                    (turn - core::f32::consts::TAU / 16.0).abs() < 1e-3,
                    "{turn}"
                );
            }
        }
        // Uniform in area and in angle over many fans.
        assert!((7_200..8_800).contains(&inner), "{inner}");
        for n in sector {
            assert!((3_700..4_300).contains(&n), "{sector:?}");
        }
    }

    #[test]
    fn ellipse_samples_are_inside_and_fill_it() {
        let mut rng = XorShiftRng::seed_from_u64(11);
        let (f1, f2) = (Point::new(0.0, 0.0), Point::new(8.0, 6.0));
        let e = Ellipse::new(f1, f2, 12.0).unwrap();
        let (mut max_u, mut left) = (0.0f32, 0);
        for _ in 0..20_000 {
            let p = e.sample(&mut rng);
            assert!(p.dist(f1) + p.dist(f2) <= 12.0 + 1e-3);
            assert!(e.contains(p));
            max_u = max_u.max(p.dist(Point::new(4.0, 3.0)));
            if (p - f1).dot(f2 - f1) < 50.0 {
                left += 1;
            }
        }
        assert!(max_u > 5.9, "samples reach the ends of the major axis");
        assert!(
            (9_500..10_500).contains(&left),
            "symmetric about the centre: {left}"
        );
        assert!(
            Ellipse::new(f1, f2, 9.0).is_none(),
            "shorter than the focal distance"
        );
        assert!(Ellipse::new(f1, f2, f32::INFINITY).is_none());
    }
}
