//! The paper's names: Table 1's 20 planners are the four rows of switches (original, `-1`
//! bidirectional, `-2` new rewiring, `Bi-` both) over five columns of a base and a metric
//! (RT-RRT*, RT-RRT*(D), AM-RRT*(E), AM-RRT*(D), AM-RRT*(G)). A [`Named`] planner is a
//! configuration and the kind of metric it runs with; the name is written from both, with
//! ` tuned` for the tuned set's tactics.

use core::fmt;

use super::{Base, Config, MetricKind, Tactics};

/// A planner as the paper names it: a configuration and the kind of metric it runs with.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Named {
    /// The metric it runs with (the planner's metric must be of this kind).
    pub metric: MetricKind,
    /// Its configuration.
    pub cfg: Config,
}

impl Default for Named {
    /// The tuned Bi-AM-RRT*(D) ([`Config::default`]).
    fn default() -> Self {
        Self {
            metric: MetricKind::Diffusion,
            cfg: Config::default(),
        }
    }
}

impl Named {
    /// The 20 planners of the paper's Table 1, row by row: original, bidirectional only (`-1`),
    /// new rewiring only (`-2`), both (`Bi-`); in each row RT-RRT*, RT-RRT*(D), AM-RRT*(E),
    /// AM-RRT*(D), AM-RRT*(G).
    #[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)] // 4 x 5 fixed loops
    pub const fn table1() -> [Named; 20] {
        let columns = [
            (Base::RtRrt, MetricKind::Euclidean),
            (Base::RtRrt, MetricKind::Diffusion),
            (Base::AmRrt, MetricKind::Euclidean),
            (Base::AmRrt, MetricKind::Diffusion),
            (Base::AmRrt, MetricKind::Geodesic),
        ];
        let first = Named {
            metric: MetricKind::Euclidean,
            cfg: Config::new(Base::RtRrt),
        };
        let mut out = [first; 20];
        let mut row = 0;
        while row < 4 {
            let mut col = 0;
            while col < 5 {
                let (base, metric) = columns[col];
                out[row * 5 + col] = Named {
                    metric,
                    cfg: Config::new(base)
                        .with_bidirectional(row == 1 || row == 3)
                        .with_new_rewiring(row == 2 || row == 3),
                };
                col += 1;
            }
            row += 1;
        }
        out
    }

    /// The planner with this Table 1 name (e.g. `"Bi-AM-RRT*(D)"`, `"RT-RRT*-2"`), or its
    /// tuned version with the suffix `" tuned"` (`"Bi-AM-RRT*(D) tuned"`).
    pub fn from_name(name: &str) -> Option<Self> {
        let tuned = Self::table1().map(Self::tuned);
        Self::table1()
            .into_iter()
            .chain(tuned)
            .find(|n| n.name() == name)
    }

    /// The tuned version ([`Config::tuned`]).
    pub const fn tuned(self) -> Self {
        Self {
            metric: self.metric,
            cfg: self.cfg.tuned(),
        }
    }

    /// The paper's version: the same metric, Table 2's parameters and no tactics (the
    /// configuration [`Config::new`] gives with its two switches).
    pub const fn paper(self) -> Self {
        Self {
            metric: self.metric,
            cfg: Config::new(self.cfg.base)
                .with_bidirectional(self.cfg.bidirectional)
                .with_new_rewiring(self.cfg.new_rewiring),
        }
    }

    /// Its name (a `Display` value).
    pub const fn name(&self) -> PlannerName {
        PlannerName(*self)
    }
}

/// The paper's Table 1 name of a planner, e.g. `Bi-AM-RRT*(D)`, `RT-RRT*(D)-1`; ` tuned`
/// with every tactic, ` +connect` (and so on) with some.
#[derive(Clone, Copy, Debug)]
pub struct PlannerName(pub(super) Named);

impl fmt::Display for PlannerName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Named { metric, cfg: c } = &self.0;
        let both = c.bidirectional && c.new_rewiring;
        if both {
            f.write_str("Bi-")?;
        }
        match (c.base, metric) {
            (Base::RtRrt, MetricKind::Euclidean) => f.write_str("RT-RRT*")?,
            (Base::RtRrt, m) => write!(f, "RT-RRT*({})", m.letter())?,
            (Base::AmRrt, m) => write!(f, "AM-RRT*({})", m.letter())?,
        }
        if !both && c.bidirectional {
            f.write_str("-1")?;
        }
        if !both && c.new_rewiring {
            f.write_str("-2")?;
        }
        if c.tactics == Tactics::TUNED {
            f.write_str(" tuned")?;
        } else if c.tactics != Tactics::NONE {
            // Some tactics: named one by one, so the name says what runs.
            for (name, on) in Tactics::NAMES.iter().zip(c.tactics.as_array()) {
                if on {
                    write!(f, " +{name}")?;
                }
            }
        }
        Ok(())
    }
}

impl PartialEq<&str> for PlannerName {
    fn eq(&self, other: &&str) -> bool {
        // Compare without allocating: write into a comparer.
        struct Cmp<'a>(&'a str, bool);
        impl fmt::Write for Cmp<'_> {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                if self.1 && self.0.starts_with(s) {
                    self.0 = &self.0[s.len()..];
                } else {
                    self.1 = false;
                }
                Ok(())
            }
        }
        let mut c = Cmp(other, true);
        let _ = fmt::write(&mut c, format_args!("{self}"));
        c.1 && c.0.is_empty()
    }
}
