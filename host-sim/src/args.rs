//! Option groups and helpers shared by the commands: the robot's body, the metric table, maps
//! given on the command line.

use std::path::PathBuf;

use anyhow::{Result, bail};
use bi_am_rrt::metric::ElementKind;
use clap::{Args, ValueEnum};
use host_sim::metric::diffusion::{TableLayout, TableOptions};
use host_sim::scenario;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum MetricArg {
    Diffusion,
    Geodesic,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum KindArg {
    I16,
    F32,
}

pub(crate) fn kind_of(k: KindArg) -> ElementKind {
    match k {
        KindArg::I16 => ElementKind::I16,
        KindArg::F32 => ElementKind::F32,
    }
}

/// The robot's body, shared by every command that runs a planner.
#[derive(Args, Clone, Copy, Debug)]
pub(crate) struct BodyArgs {
    /// The robot's radius in metres: every path keeps the disc clear of the walls and
    /// obstacles (default: the scenario file's `robot_radius_m`, else 0, a point).
    #[arg(long, value_name = "METRES")]
    robot_radius: Option<f32>,
    /// Move a start or goal where the robot's disc has no room to the nearest position where
    /// it has, and say how far (without it such a scenario is refused, naming that position).
    #[arg(long)]
    snap_to_room: bool,
    /// Prefer paths that keep this many metres beyond the robot's body where the space
    /// allows (a cost that rises near walls, as nav2's inflation layer: see docs/guides/body.md;
    /// default: none, every edge costs its length).
    #[arg(long, value_name = "METRES")]
    clearance_margin: Option<f32>,
    /// How much more a metre costs at the body's edge than in open space, with
    /// --clearance-margin.
    #[arg(
        long,
        value_name = "W",
        default_value_t = 1.0,
        requires = "clearance_margin"
    )]
    clearance_weight: f32,
}

impl BodyArgs {
    /// The scenario for the robot these flags name (unchanged without them).
    pub(crate) fn apply(&self, sc: scenario::Scenario) -> Result<scenario::Scenario> {
        let radius = self.robot_radius.unwrap_or(sc.robot_radius);
        let sc = if self.robot_radius.is_none() && !self.snap_to_room {
            sc
        } else {
            sc.with_body(radius, self.snap_to_room)?
        };
        match self.clearance_margin {
            Some(m) => sc.with_clearance(m, self.clearance_weight),
            None => Ok(sc),
        }
    }

    pub(crate) fn apply_all(
        &self,
        scs: Vec<scenario::Scenario>,
    ) -> Result<Vec<scenario::Scenario>> {
        scs.into_iter().map(|s| self.apply(s)).collect()
    }
}

/// Refuses a clearance preference (`--clearance-margin`, or a scenario file's
/// `clearance_margin_m`) on a command that cannot honour it, saying `why`.
pub(crate) fn no_clearance(scs: &[scenario::Scenario], why: &str) -> Result<()> {
    match scs.iter().find(|s| s.clearance.is_some()) {
        Some(s) => bail!(
            "scenario {}: a clearance preference is not supported here: {why}",
            s.name
        ),
        None => Ok(()),
    }
}

/// The diffusion table options shared by `experiment`, `bake` and `export`.
#[derive(Args)]
pub(crate) struct TableArgs {
    /// Diffusion table element type.
    #[arg(long, value_enum, default_value = "i16")]
    table_kind: KindArg,
    /// Diffusion table: map cells per block along each axis (0: the block side that fits
    /// --max-bytes with the smallest error).
    #[arg(long, default_value_t = 0)]
    coarsen: u16,
    /// Diffusion table: size budget in bytes when --coarsen is 0 (0: 128 KiB, plus the piece
    /// map's half byte per cell beyond 32 KiB on maps over 65,536 cells).
    #[arg(long, default_value_t = 0)]
    max_bytes: usize,
    /// Diffusion bake: most memory it may use, in MiB (estimated before it starts; a larger
    /// bake is refused with its estimate).
    #[arg(long, default_value_t = host_sim::metric::diffusion::DEFAULT_MAX_MEMORY >> 20)]
    max_memory: usize,
    /// Diffusion bake: compute the map on every free cell (`cells`), on the table's pieces
    /// (`pieces`), or `auto` (cells up to 65,536 free cells, pieces above).
    #[arg(long, value_enum, default_value = "auto")]
    basis: host_sim::metric::diffusion::BasisChoice,
    /// Diffusion table layout: `pieces` (one entry per connected free piece of a block,
    /// never across a wall) or `uniform` (one entry per block, the format-1 table).
    #[arg(long, value_enum, default_value = "pieces")]
    layout: TableLayout,
}

impl TableArgs {
    pub(crate) fn options(self) -> TableOptions {
        TableOptions {
            kind: kind_of(self.table_kind),
            coarsen: self.coarsen,
            max_bytes: self.max_bytes,
            layout: self.layout,
            max_memory: self.max_memory << 20,
            basis: self.basis,
            map_hash: None,
            keep: None,
        }
    }
}

pub(crate) fn load_map(spec: &str, resolution: Option<f32>) -> Result<scenario::OwnedGrid> {
    let mut grid = match spec.strip_prefix("builtin:") {
        Some(name) => scenario::builtin_by_name(name)?.map,
        None if spec.ends_with(".yaml") || spec.ends_with(".yml") => {
            if resolution.is_some() {
                bail!("--resolution is for PNG maps: a ROS map's YAML gives its own");
            }
            scenario::load_ros_yaml(&PathBuf::from(spec))?.grid
        }
        None => scenario::load_png(&PathBuf::from(spec))?,
    };
    if let Some(r) = resolution {
        scenario::check_resolution("--resolution", r)?;
        grid.cell_bits = r.to_bits();
    }
    Ok(grid)
}

/// The planners a command runs: one flag, one syntax and one default for every command
/// (`host_sim::sim::planners::parse_variants`).
#[derive(Args, Clone, Debug)]
pub(crate) struct PlannerArgs {
    /// Planners, comma-separated: `tuned` (the tuned Bi-AM-RRT*(D), the default), `paper`
    /// (the paper's Bi-AM-RRT*(D)), `all` (Table 1's 20) or Table 1 names (any case, with or
    /// without the suffix " tuned"), each optionally with `@field=value` overrides (any value
    /// `host-sim params` lists), e.g. "tuned@e_max=8,paper". `--planner` is the old
    /// spelling.
    #[arg(
        long = "planners",
        alias = "planner",
        value_name = "LIST",
        default_value = host_sim::sim::planners::DEFAULT_PLANNERS
    )]
    planners: String,
}

impl PlannerArgs {
    /// Every planner, with its overrides.
    pub(crate) fn variants(&self) -> Result<Vec<host_sim::sim::planners::Variant>> {
        host_sim::sim::planners::parse_variants(&self.planners)
    }

    /// Every planner, for a command that takes no overrides.
    pub(crate) fn named(&self) -> Result<Vec<bi_am_rrt::Named>> {
        host_sim::sim::planners::parse_planners(&self.planners)
    }

    /// The one planner of a command that runs one.
    pub(crate) fn one(&self) -> Result<host_sim::sim::planners::Variant> {
        host_sim::sim::planners::one(&self.planners)
    }
}

/// Old spellings of options that still work for one release, each with the new one: a
/// warning is printed when a command line uses one (`main`).
pub(crate) const RENAMED: [(&str, &str); 3] = [
    ("--planner", "--planners"),
    ("--scenario", "--maps"),
    ("--builtin", "--maps"),
];

/// Warns about each old spelling in `args` ([`RENAMED`]).
pub(crate) fn warn_renamed(args: &[String]) {
    for (old, new) in RENAMED {
        if args
            .iter()
            .any(|a| a == old || a.starts_with(&format!("{old}=")))
        {
            eprintln!("warning: {old} is now {new} ({old} goes in the next release)");
        }
    }
}

/// The scenarios a command runs: one group, one syntax for every command. A scenario file
/// (or the built-ins), the names to take from it, and the robot's body.
#[derive(Args, Clone, Debug)]
pub(crate) struct ScenarioArgs {
    /// Scenario file (TOML in the form of shared/maps/scenarios.toml; map paths relative to
    /// it), or `builtin` for the built-in scenarios (open, bug_trap, maze and the paper-sized
    /// trap_100, maze_100, office_200), the default.
    #[arg(long, value_name = "FILE")]
    scenarios: Option<PathBuf>,
    /// Scenario names in --scenarios, comma-separated (default: every one; a command that
    /// runs one scenario: its own default among the built-ins). `--scenario` and `--builtin`
    /// are the old spellings.
    #[arg(
        long,
        value_name = "NAMES",
        value_delimiter = ',',
        alias = "scenario",
        alias = "builtin"
    )]
    maps: Option<Vec<String>>,
    #[command(flatten)]
    body: BodyArgs,
}

impl ScenarioArgs {
    fn file(&self) -> PathBuf {
        self.scenarios
            .clone()
            .unwrap_or_else(|| PathBuf::from(scenario::BUILTIN_SET))
    }

    /// Every scenario named (all of the file's without names), for the robot's body.
    pub(crate) fn all(&self) -> Result<Vec<scenario::Scenario>> {
        self.body.apply_all(scenario::load_scenarios(
            &self.file(),
            self.maps.as_deref(),
        )?)
    }

    /// [`ScenarioArgs::all`], or `fallback`'s scenarios when neither a file nor names are
    /// given.
    pub(crate) fn all_or(
        &self,
        fallback: impl FnOnce() -> Vec<scenario::Scenario>,
    ) -> Result<Vec<scenario::Scenario>> {
        if self.scenarios.is_none() && self.maps.is_none() {
            self.body.apply_all(fallback())
        } else {
            self.all()
        }
    }

    /// The one scenario of a command that runs one: the one named, or the built-in
    /// `default` when no file and no name are given.
    pub(crate) fn one(&self, default: Option<&str>) -> Result<scenario::Scenario> {
        let names = match (&self.maps, &self.scenarios, default) {
            (Some(names), _, _) => names.clone(),
            (None, None, Some(d)) => vec![d.to_string()],
            _ => bail!("name the scenario to run with --maps NAME"),
        };
        if names.len() != 1 {
            bail!(
                "this command runs one scenario; --maps names {}",
                names.len()
            );
        }
        let sc = scenario::load_scenarios(&self.file(), Some(&names))?.remove(0);
        self.body.apply(sc)
    }
}

/// The paper's setting beyond its planners, one group for every command that plans: how
/// the lengths, Algorithms 4-6 and the rewiring budgets, and the work per call follow the
/// paper. "paper" means one thing on the command line: `--planners paper` (or `all`) is the
/// paper's planner with Table 2's parameters, and `--paper` runs it the way the paper did
/// (everything below at once).
#[derive(Args, Clone, Debug)]
pub(crate) struct FidelityArgs {
    /// The paper's whole setting: Table 2's lengths, Algorithms 4-6 and the Meet as printed
    /// and, where a command has a pace, the paper's (with --clock virtual). With
    /// `--planners paper` or `all`: the paper's planners as the paper ran them.
    #[arg(long)]
    paper: bool,
    /// Table 2's lengths in metres as printed (e_max 5 m, sigma 30 m, ...) instead of
    /// the lengths that follow the map (the default: Table 2's on maps 100-200 m across,
    /// proportional to the map's size off that range; docs/guides/configurations.md, "Lengths that follow the map").
    #[arg(long)]
    paper_lengths: bool,
    /// Parts of Algorithms 4-6 and the Meet run exactly as printed instead of this crate's
    /// reading (src/rewire/mod.rs): `all`, `none`, or a comma-separated list of alg4-take
    /// (Algorithm 4 dequeues x_r2), alg4-free (Algorithm 4 enqueues only neighbours x_r1
    /// sees), alg5-gate (Algorithm 5 runs Algorithm 6 only on lists longer than two),
    /// alg6-take (Algorithm 6 pops x_r2), alg6-cost (Algorithm 6's cost test through x_r1),
    /// alg6-clear (Algorithm 6's clearing test on Second(S)), alg6-clear-outside (the
    /// clearing test also after an x_r1 outside the ellipse), meet-all-pairs (the Meet tests
    /// every pair within sigma).
    #[arg(long, value_name = "PARTS", default_value = "none")]
    as_printed: String,
    /// The reference's rewiring budgets: every expansion spends its full t_root / t_goal
    /// (default: 24 visits per phase and expansion).
    #[arg(long)]
    faithful: bool,
    /// Work per call: `full` (as much as t_exp allows here) or `paper` (the paper's pace:
    /// 20 tree expansions, each tree's counting, and 8 rewiring visits per phase and
    /// expansion, every call lasting its full t_exp on the virtual clock; needs --clock
    /// virtual).
    #[arg(long, value_enum, default_value = "full")]
    pace: host_sim::results::Pace,
}

impl FidelityArgs {
    /// Table 2's lengths as printed.
    pub(crate) fn paper_lengths(&self) -> bool {
        self.paper || self.paper_lengths
    }

    /// The parts of Algorithms 4-6 and the Meet run as printed.
    pub(crate) fn as_printed(&self) -> Result<bi_am_rrt::AsPrinted> {
        if self.paper {
            return Ok(bi_am_rrt::AsPrinted::ALL);
        }
        host_sim::sim::planners::parse_as_printed(&self.as_printed)
    }

    /// The reference's rewiring budgets.
    pub(crate) fn faithful(&self) -> bool {
        self.faithful
    }

    /// The work per call.
    pub(crate) fn pace(&self) -> host_sim::results::Pace {
        if self.paper {
            host_sim::results::Pace::Paper
        } else {
            self.pace
        }
    }

    /// The reading and the budgets on each planner's named configuration (before its
    /// lengths are fitted and its overrides applied: an override of the same value wins),
    /// for a command whose study does not take them itself; refuses the paper's pace where
    /// the command has none.
    pub(crate) fn apply(
        &self,
        variants: &mut [host_sim::sim::planners::Variant],
        has_pace: bool,
    ) -> Result<()> {
        if !has_pace && self.pace == host_sim::results::Pace::Paper {
            bail!("this command has no pace: --pace paper is for run and experiment");
        }
        let printed = self.as_printed()?;
        for v in variants {
            v.edit_named(|c| {
                c.as_printed = printed;
                if self.faithful {
                    c.rewiring.mode = bi_am_rrt::RewireMode::Faithful;
                }
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Line {
        #[command(flatten)]
        fidelity: FidelityArgs,
        #[command(flatten)]
        planners: PlannerArgs,
    }

    /// `--paper` is the paper's whole setting; without it, this crate's reading at full
    /// speed; a command without a pace refuses the paper's.
    #[test]
    fn paper_is_one_setting() {
        let line = Line::try_parse_from(["t", "--paper", "--planners", "paper"]).unwrap();
        let f = &line.fidelity;
        assert!(f.paper_lengths());
        assert_eq!(f.as_printed().unwrap(), bi_am_rrt::AsPrinted::ALL);
        assert_eq!(f.pace(), host_sim::results::Pace::Paper);
        let mut v = line.planners.variants().unwrap();
        f.apply(&mut v, true).unwrap();
        assert_eq!(v[0].named.cfg.as_printed, bi_am_rrt::AsPrinted::ALL);
        assert_eq!(v[0].named.cfg.tactics, bi_am_rrt::Tactics::NONE);

        let line = Line::try_parse_from(["t"]).unwrap();
        let f = &line.fidelity;
        assert!(!f.paper_lengths());
        assert_eq!(f.as_printed().unwrap(), bi_am_rrt::AsPrinted::NONE);
        assert_eq!(f.pace(), host_sim::results::Pace::Full);
        let mut v = line.planners.variants().unwrap();
        let before = v[0].named;
        f.apply(&mut v, false).unwrap();
        assert_eq!(v[0].named, before, "the defaults change nothing");

        let line = Line::try_parse_from(["t", "--pace", "paper", "--faithful"]).unwrap();
        let mut v = line.planners.variants().unwrap();
        assert!(line.fidelity.apply(&mut v, false).is_err());
        line.fidelity.apply(&mut v, true).unwrap();
        assert_eq!(
            v[0].named.cfg.rewiring.mode,
            bi_am_rrt::RewireMode::Faithful
        );
    }
}
