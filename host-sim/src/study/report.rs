//! The `report` command: a results folder (`results`) turned into charts (`plotters`, SVG and
//! PNG) and a Markdown document, in the shape of the paper's Section 5:
//!
//! - Fig. 6 (a)-(c): for each scheme (`-1` bidirectional search, `-2` the new rewiring, `Bi-`
//!   both), the mean search time and mean path length of the five base planners, original
//!   against modified, per map, with the change in percent;
//! - box plots per planner and map of the search time and of travelled / optimal;
//! - the nodes in the tree when the goal joined (the paper's Section 6 argument);
//! - Table 3, the map-processing times, from the manifest;
//! - a headline table per map (every planner: search time median and quartiles, means, path,
//!   travelled / optimal, nodes at goal, change against its original planner), and the
//!   paper's own claims next to the measured changes.
//!
//! Only goal 1 of each run enters (the paper's experiment is start to goal 1). A folder that is
//! not complete is reported as it is, with the count of runs it holds.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use plotters::prelude::*;

use crate::draw::chart::*;
use crate::results::stats::{Spread, mean};
use crate::results::{Manifest, Row, read_rows};

/// The paper's scheme of a planner name: `Original`, `-1`, `-2` or `Bi-`, and the name of
/// its original planner.
fn scheme(name: &str) -> Option<(Scheme, String)> {
    let base = name.strip_suffix(" tuned").unwrap_or(name);
    let n = bi_am_rrt::Named::from_name(base)?;
    let c = n.cfg;
    let s = match (c.bidirectional, c.new_rewiring) {
        (false, false) => Scheme::Original,
        (true, false) => Scheme::Bidirectional,
        (false, true) => Scheme::Rewiring,
        (true, true) => Scheme::Both,
    };
    let orig = c.with_bidirectional(false).with_new_rewiring(false);
    let mut o = orig.name(n.metric).to_string();
    if base.len() != name.len() {
        o.push_str(" tuned");
    }
    Some((s, o))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scheme {
    Original,
    Bidirectional,
    Rewiring,
    Both,
}

impl Scheme {
    fn label(self) -> &'static str {
        match self {
            Scheme::Original => "original",
            Scheme::Bidirectional => "(a) bidirectional search (-1)",
            Scheme::Rewiring => "(b) new rewiring (-2)",
            Scheme::Both => "(c) both (Bi-)",
        }
    }
}

/// What the paper states for each scheme (Section 5.2, Table 3), for the comparison table.
const PAPER_CLAIMS: &[(&str, &str)] = &[
    (
        "(a) bidirectional search (-1)",
        "search time -69 % (bug_trap), -40.1 % (maze), -41.7 % (office); path length +0.8 %; \
         AM-RRT*(E)-1 search time -75.6 % on bug_trap",
    ),
    (
        "(b) new rewiring (-2)",
        "path length -2.2 % on average; AM-RRT*(D)-2 on office: path -3 %, search time -5.6 %",
    ),
    (
        "(c) both (Bi-)",
        "Bi-AM-RRT*(D): search time -24.6 / -45.2 / -44.9 %, path -1.4 / -0.7 / -2.8 % \
         (bug_trap / maze / office); Bi-AM-RRT*(E): search time -76.7 %, path +2.6 % on average; \
         Bi-RT-RRT* and Bi-AM-RRT*(E) paths longer on bug_trap",
    ),
    (
        "nodes at goal",
        "bug_trap: RT-RRT* 445, AM-RRT*(E) 1,062, AM-RRT*(D) 76 on average",
    ),
    (
        "map processing (Table 3)",
        "diffusion 1.5 / 1.5 / 5.6 s, geodesic 49 / 49 / 232 s (bug_trap / maze / office)",
    ),
];

/// Per planner and map: the goal-1 statistics the report uses.
struct Cell {
    runs: usize,
    reached: usize,
    /// Runs in which goal 1 joined the tree (all a `--search-only` run measures).
    found: usize,
    collisions: u32,
    /// Search time read at the end of the call in which the goal joined (the reference's
    /// definition, the primary figure; the join instant for rows made before issue 24).
    search_s: Vec<f64>,
    /// The instant the goal joined the forward tree.
    join_s: Vec<f64>,
    path_m: Vec<f64>,
    ratio: Vec<f64>,
    nodes: Vec<f64>,
    /// Nodes at the end of the call in which the goal joined (the reference's count).
    nodes_end: Vec<f64>,
    /// Fig. 7: seconds from the disc's drop to a free path again.
    replan_s: Vec<f64>,
    /// Fig. 7: travelled from the drop / the exact optimum around the disc.
    detour: Vec<f64>,
    /// Collisions of each run.
    collisions_per_run: Vec<f64>,
}

impl Cell {
    fn of(rows: &[&Row]) -> Self {
        let reached: Vec<&&Row> = rows.iter().filter(|r| r.reached).collect();
        Self {
            runs: rows.len(),
            reached: reached.len(),
            found: rows.iter().filter(|r| r.search_time_s.is_some()).count(),
            collisions: rows.iter().map(|r| r.collisions).sum(),
            search_s: rows
                .iter()
                .filter_map(|r| r.search_time_call_end_s.or(r.search_time_s))
                .collect(),
            join_s: rows.iter().filter_map(|r| r.search_time_s).collect(),
            path_m: reached
                .iter()
                .filter_map(|r| r.path_length_m.map(f64::from))
                .collect(),
            ratio: reached
                .iter()
                .filter_map(|r| r.travelled_ratio.map(f64::from))
                .collect(),
            nodes: rows
                .iter()
                .filter_map(|r| r.nodes_at_goal.map(|n| n as f64))
                .collect(),
            nodes_end: rows
                .iter()
                .filter_map(|r| r.nodes_at_call_end.map(|n| n as f64))
                .collect(),
            replan_s: rows.iter().filter_map(|r| r.replan_s).collect(),
            collisions_per_run: rows.iter().map(|r| f64::from(r.collisions)).collect(),
            detour: rows
                .iter()
                .filter_map(|r| {
                    Some(f64::from(r.travelled_after_drop_m?) / f64::from(r.optimal_after_drop_m?))
                })
                .collect(),
        }
    }

    /// The sample a notes quote names (`search`, `join`, `path`, `ratio`, `nodes`,
    /// `nodes_end`, `replan`, `detour`).
    fn measure(&self, name: &str) -> Result<&[f64]> {
        Ok(match name {
            "search" => &self.search_s,
            "join" => &self.join_s,
            "path" => &self.path_m,
            "ratio" => &self.ratio,
            "nodes" => &self.nodes,
            "nodes_end" => &self.nodes_end,
            "replan" => &self.replan_s,
            "detour" => &self.detour,
            "collisions" => &self.collisions_per_run,
            _ => anyhow::bail!(
                "measure {name:?}: search, join, path, ratio, nodes, nodes_end, replan, detour \
                 or collisions"
            ),
        })
    }

    fn search_mean(&self) -> Option<f64> {
        mean(&self.search_s)
    }

    fn join_mean(&self) -> Option<f64> {
        mean(&self.join_s)
    }

    fn path_mean(&self) -> Option<f64> {
        mean(&self.path_m)
    }
}

/// A value of the measure `name` ([`Cell::measure`]) as the notes quote it: times in ms,
/// ratios with three decimals, node counts whole.
fn show_measure(name: &str, v: Option<f64>) -> String {
    match (name, v) {
        (_, None) => "-".to_string(),
        ("ratio" | "detour", Some(v)) => format!("{v:.3}"),
        ("nodes" | "nodes_end" | "collisions", Some(v)) => format!("{v:.0}"),
        ("search" | "join" | "replan", Some(v)) => num(v * 1e3),
        (_, Some(v)) => num(v),
    }
}

fn change(orig: Option<f64>, new: Option<f64>) -> Option<f64> {
    match (orig, new) {
        (Some(o), Some(n)) if o > 0.0 => Some(100.0 * (n - o) / o),
        _ => None,
    }
}

fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |p| format!("{p:+.1} %"))
}

/// A change with the Mann-Whitney p-value of the two samples behind it, e.g. `-0.4 % (p
/// 0.62)`: a p above 0.05 means the change is within seed noise.
fn pct_p(v: Option<f64>, orig: &[f64], new: &[f64]) -> String {
    match (v, crate::results::stats::mann_whitney_p(orig, new)) {
        (Some(c), Some(p)) => format!("{c:+.1} % (p {p:.2})"),
        (v, _) => pct(v),
    }
}

fn opt(v: Option<f64>, scale: f64) -> String {
    v.map_or_else(|| "-".into(), |x| num(x * scale))
}

/// What `report` wrote.
#[derive(Debug)]
pub struct Report {
    /// The Markdown file.
    pub markdown: PathBuf,
    /// Charts written (stems; each as .svg and .png).
    pub charts: Vec<PathBuf>,
}

/// Writes the report of the results folder `results` to `out` (a `.md` file); the charts go
/// to the folder `charts` beside it (one folder per study: `docs/results/pace/README.md`,
/// `notes.md`, `data/`, `charts/`). `notes`
/// (Markdown written by hand, e.g. how the results compare with the paper's) goes after the
/// settings, so regenerating the report keeps it.
pub fn report(results: &Path, out: &Path, command: &str, notes: Option<&str>) -> Result<Report> {
    let manifest = Manifest::read(results)?
        .with_context(|| format!("{} has no experiment.json", results.display()))?;
    let rows = read_rows(results, false)?;
    let goal1: Vec<&Row> = rows.iter().filter(|r| r.goal_index == 1).collect();
    let settings = &manifest.settings;
    let maps: Vec<String> = settings
        .scenarios
        .iter()
        .map(|s| s.name.clone())
        .filter(|m| goal1.iter().any(|r| &r.scenario == m))
        .collect();
    let planners: Vec<String> = settings
        .planners
        .iter()
        .filter(|p| goal1.iter().any(|r| &r.planner == *p))
        .cloned()
        .collect();
    let chart_dir = out.parent().unwrap_or(Path::new(".")).join("charts");
    std::fs::create_dir_all(&chart_dir).with_context(|| format!("{}", chart_dir.display()))?;
    let rel = chart_dir
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default();
    let page = Page {
        settings,
        goal1,
        maps,
        planners,
        chart_dir,
        rel,
    };
    let mut charts = Vec::new();
    let mut md = String::new();
    let done = crate::results::done_runs(&rows).len();
    let wanted = manifest.runs().len();
    let _ = writeln!(
        md,
        "# Results: the paper's experiment, measured{}\n",
        match settings.obstacle_m {
            Some(r) => format!(" with a disc of {r} m dropped on the path (Fig. 7)"),
            None => String::new(),
        }
    );
    let _ = writeln!(
        md,
        "Generated by `{command}` from `{}` ({done} of {wanted} runs{}; {}). Regenerate with the \
         same command; the experiment itself is in the folder's `experiment.json`.\n",
        results.display(),
        if done < wanted {
            ", **incomplete**"
        } else {
            ""
        },
        manifest.tool
    );
    let _ = writeln!(
        md,
        "Settings: {} repeats (seeds {}-{}), clock `{:?}`, goals `{:?}`, `t_exp` {}, rewiring {}, \
         anytime column {} ms, diffusion table {}. Statistics are over the runs' goal 1 (start \
         to goal 1, as the paper): medians with the interquartile range, and means where the \
         paper reports means (Fig. 6).\n",
        settings.repeats,
        settings.seed,
        settings.seed + u64::from(settings.repeats.max(1)) - 1,
        settings.clock,
        settings.goals,
        settings
            .t_exp_ms
            .map_or("150 ms (the paper's)".into(), |t| format!("{t} ms")),
        if settings.pace == crate::results::Pace::Paper {
            "at the paper's pace (20 expansions per call, 8 visits per phase and expansion, \
             every call lasting its full t_exp)"
        } else if settings.faithful {
            "the reference's time budgets"
        } else {
            "24 visits per phase and expansion"
        },
        settings.anytime_ms,
        settings.table
    );

    // The notes go here once every figure they may quote is known (`fill`).
    let notes_at = md.len();

    let scheme_changes = fig6_charts(&page, &mut charts)?;
    box_plots(&page, &mut charts)?;
    fig6_claims(&page, &scheme_changes, &charts, &mut md);
    planner_tables(&page, &mut md);
    // Fig. 7: a disc dropped on the path.
    if page.goal1.iter().any(|r| r.disc_r_m.is_some()) {
        fig7(
            &mut md,
            &mut charts,
            &page.goal1,
            &page.planners,
            &page.maps,
            settings,
            &page.chart_dir,
            &page.rel,
        )?;
    }
    if let Some(n) = notes {
        let filled = fill(n, |args| resolve_note(&page, &scheme_changes, args))
            .context("the notes quote the data")?;
        md.insert_str(notes_at, &format!("{}\n\n", filled.trim_end()));
    }
    table3(&manifest, &mut md);
    if let Some(dir) = out.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(out, md).with_context(|| format!("{}", out.display()))?;
    Ok(Report {
        markdown: out.to_path_buf(),
        charts,
    })
}

/// What every part of a report reads: the folder's goal-1 rows, its maps and planners in the
/// matrix's order, and where the charts go (`rel`: that folder as the page links it).
struct Page<'a> {
    settings: &'a crate::results::Settings,
    goal1: Vec<&'a Row>,
    maps: Vec<String>,
    planners: Vec<String>,
    chart_dir: PathBuf,
    rel: String,
}

impl Page<'_> {
    /// The goal-1 rows of planner `p` on map `m`.
    /// The goal-1 runs of planner `p` (`*`: every planner) on map `m`.
    fn cell(&self, p: &str, m: &str) -> Cell {
        let rs: Vec<&Row> = self
            .goal1
            .iter()
            .filter(|r| (p == "*" || r.planner == p) && r.scenario == m)
            .copied()
            .collect();
        Cell::of(&rs)
    }
}

/// A scheme's change on one map: the scheme, the map, the changes of the mean search time
/// (call end), of the mean join instant and of the mean path, and the originals averaged.
type SchemeChange = (
    Scheme,
    String,
    Option<f64>,
    Option<f64>,
    Option<f64>,
    Vec<String>,
);

/// Fig. 6: one chart per scheme (each original against its modified planner), and each
/// scheme's change of the means per map.
fn fig6_charts(page: &Page<'_>, charts: &mut Vec<PathBuf>) -> Result<Vec<SchemeChange>> {
    let Page {
        settings,
        goal1,
        maps,
        planners,
        chart_dir,
        ..
    } = page;
    let cell = |p: &str, m: &str| page.cell(p, m);
    let mut scheme_changes: Vec<SchemeChange> = Vec::new();
    for sch in [Scheme::Bidirectional, Scheme::Rewiring, Scheme::Both] {
        let pairs: Vec<(String, String)> = planners
            .iter()
            .filter_map(|p| {
                let (s, o) = scheme(p)?;
                (s == sch && planners.contains(&o)).then(|| (o, p.clone()))
            })
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let mut panels = Vec::new();
        for (what, log) in [
            ("search time, mean (ms)", true),
            ("path length, mean (m)", false),
        ] {
            for m in maps {
                let mut values = Vec::new();
                let mut notes = Vec::new();
                for (o, p) in &pairs {
                    let (co, cp) = (cell(o, m), cell(p, m));
                    let (vo, vp) = if log {
                        (
                            co.search_mean().map(|s| s * 1e3),
                            cp.search_mean().map(|s| s * 1e3),
                        )
                    } else {
                        (co.path_mean(), cp.path_mean())
                    };
                    notes.push(change(vo, vp).map(|c| format!("{c:+.1}%")));
                    values.push(vec![vo, vp]);
                }
                let optimum = goal1
                    .iter()
                    .find(|r| &r.scenario == m)
                    .and_then(|r| r.optimal_m)
                    .map(f64::from);
                panels.push(BarPanel {
                    title: format!("{m}: {what}"),
                    y_label: if log { "ms (log)".into() } else { "m".into() },
                    log,
                    groups: pairs.iter().map(|(o, _)| o.clone()).collect(),
                    series: vec![
                        (RGBColor(150, 150, 150), "original".into()),
                        (RGBColor(40, 90, 180), "modified".into()),
                    ],
                    reference: optimum
                        .filter(|_| !log)
                        .map(|o| (o, format!("exact optimum {o:.2} m"))),
                    from_zero: false,
                    values,
                    notes,
                });
            }
        }
        panels.retain(|p| p.values.iter().flatten().any(Option::is_some));
        let file = chart_dir.join(match sch {
            Scheme::Bidirectional => "fig6a",
            Scheme::Rewiring => "fig6b",
            _ => "fig6c",
        });
        render(
            &Bars {
                title: format!(
                    "Fig. 6 {}: each original against its modified planner",
                    sch.label()
                ),
                cols: maps.len().max(1),
                panels,
            },
            &file,
        )?;
        charts.push(file);
        for m in maps {
            // Only complete pairs: both planners with a mean search time and path length.
            let mut ds = Vec::new();
            let mut dj = Vec::new();
            let mut dp = Vec::new();
            let mut used = Vec::new();
            for (o, p) in &pairs {
                let (co, cp) = (cell(o, m), cell(p, m));
                let (s, j, l) = (
                    change(co.search_mean(), cp.search_mean()),
                    change(co.join_mean(), cp.join_mean()),
                    change(co.path_mean(), cp.path_mean()),
                );
                if let (Some(s), Some(j), Some(l)) = (s, j, l) {
                    ds.push(s);
                    dj.push(j);
                    dp.push(l);
                    used.push(o.clone());
                } else if settings.search_only
                    && let (Some(s), Some(j)) = (s, j)
                {
                    ds.push(s);
                    dj.push(j);
                    used.push(o.clone());
                }
            }
            scheme_changes.push((sch, m.clone(), mean(&ds), mean(&dj), mean(&dp), used));
        }
    }
    Ok(scheme_changes)
}

/// Box plots per map (search time, travelled / optimum, nodes at goal) of every planner.
fn box_plots(page: &Page<'_>, charts: &mut Vec<PathBuf>) -> Result<()> {
    let Page {
        settings,
        maps,
        planners,
        chart_dir,
        ..
    } = page;
    let cell = |p: &str, m: &str| page.cell(p, m);
    // Box plots and nodes at goal.
    for m in maps {
        let cells: Vec<Cell> = planners.iter().map(|p| cell(p, m)).collect();
        let file = chart_dir.join(format!("box-{m}"));
        let mut boxes = Boxes {
            title: format!(
                "{m}: every planner, goal 1 ({} runs each)",
                settings.repeats
            ),
            panels: vec![
                BoxPanel {
                    title: "search time (ms, log scale)".into(),
                    x_label: "ms".into(),
                    log: true,
                    names: planners.clone(),
                    samples: cells
                        .iter()
                        .map(|c| c.search_s.iter().map(|s| s * 1e3).collect())
                        .collect(),
                },
                BoxPanel {
                    title: "travelled / exact optimum".into(),
                    x_label: "ratio".into(),
                    log: false,
                    names: planners.clone(),
                    samples: cells.iter().map(|c| c.ratio.clone()).collect(),
                },
                BoxPanel {
                    title: "nodes in the tree when the goal joined (log)".into(),
                    x_label: "nodes".into(),
                    log: true,
                    names: planners.clone(),
                    samples: cells.iter().map(|c| c.nodes.clone()).collect(),
                },
            ],
        };
        boxes
            .panels
            .retain(|p| p.samples.iter().any(|s| !s.is_empty()));
        render(&boxes, &file)?;
        charts.push(file);
    }
    Ok(())
}

/// The Markdown of Fig. 6: the paper's claims next to the measured scheme changes.
fn fig6_claims(
    page: &Page<'_>,
    scheme_changes: &[SchemeChange],
    charts: &[PathBuf],
    md: &mut String,
) {
    let rel = &page.rel;
    // Markdown: the paper's claims next to the measured scheme changes.
    let _ = writeln!(md, "## Fig. 6: what each scheme changes\n");
    let _ = writeln!(
        md,
        "Change of the modified planner against its original (mean search time, mean path \
         length), averaged over the pairs named in the last column (the complete pairs: both \
         planners in the folder with a mean), per map. Search time is read at the end of the \
         `plan` call in which the goal joined the forward tree, as the reference reads it; \
         the join instant is beside it. The paper's figures are from its text (Section \
         5.2).\n"
    );
    let _ = writeln!(
        md,
        "| scheme | map | search time | join instant | path length | averaged over (originals) |\n|---|---|---:|---:|---:|---|"
    );
    for (sch, m, ds, dj, dp, used) in scheme_changes {
        let _ = writeln!(
            md,
            "| {} | {m} | {} | {} | {} | {} |",
            sch.label(),
            pct(*ds),
            pct(*dj),
            pct(*dp),
            if used.is_empty() {
                "none".to_string()
            } else {
                used.join(", ")
            }
        );
    }
    let _ = writeln!(md, "\n| the paper says | |\n|---|---|");
    for (k, v) in PAPER_CLAIMS {
        let _ = writeln!(md, "| {k} | {v} |");
    }
    for f in ["fig6a", "fig6b", "fig6c"] {
        if charts.iter().any(|c| c.ends_with(f)) {
            let _ = writeln!(md, "\n![{f}]({rel}/{f}.svg)");
        }
    }
}

/// Every planner per map (goal 1): the headline tables.
fn planner_tables(page: &Page<'_>, md: &mut String) {
    let Page {
        settings,
        goal1,
        maps,
        planners,
        rel,
        ..
    } = page;
    let cell = |p: &str, m: &str| page.cell(p, m);
    // Headline tables.
    let _ = writeln!(md, "\n## Every planner, per map (goal 1)\n");
    let _ = writeln!(
        md,
        "Search time: goal set until the end of the `plan` call in which the goal joined the \
         forward tree, on the run's clock (the reference's definition); joined: the instant \
         it joined, within that call. Path: travelled by the agent. Change: mean against the planner's original (Table 1 row 1), \
         with the two-sided Mann-Whitney p-value of the two samples (seeds): p above 0.05, the \
         change is within seed noise.\n"
    );
    for m in maps {
        let optimum = goal1
            .iter()
            .find(|r| &r.scenario == m)
            .and_then(|r| r.optimal_m);
        let _ = writeln!(
            md,
            "### {m}\n\nExact optimum from the start to goal 1: {}.\n",
            optimum.map_or("- (unreachable)".into(), |o| format!("{o:.2} m"))
        );
        let _ = writeln!(
            md,
            "| planner | {} | search ms, median [IQR] | search ms, mean | joined ms, median | \
             path m, mean | travelled / optimal, median [IQR] | nodes at goal, median | \
             change: search | change: path |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
            // A --search-only run stops when the goal joins: it counts goals found.
            if settings.search_only {
                "found"
            } else {
                "reached"
            }
        );
        for p in planners {
            let c = cell(p, m);
            let s = Spread::of(c.search_s.clone());
            let r = Spread::of(c.ratio.clone());
            let orig = scheme(p)
                .filter(|(s, _)| *s != Scheme::Original)
                .map(|(_, o)| cell(&o, m));
            let _ = writeln!(
                md,
                "| {p} | {}/{}{} | {} [{}, {}] | {} | {} | {} | {} [{}, {}] | {} | {} | {} |",
                if settings.search_only {
                    c.found
                } else {
                    c.reached
                },
                c.runs,
                if c.collisions > 0 {
                    format!(" ({} collisions)", c.collisions)
                } else {
                    String::new()
                },
                opt(s.median, 1e3),
                opt(s.q1, 1e3),
                opt(s.q3, 1e3),
                opt(s.mean, 1e3),
                opt(Spread::of(c.join_s.clone()).median, 1e3),
                opt(c.path_mean(), 1.0),
                r.median.map_or("-".into(), |v| format!("{v:.3}")),
                r.q1.map_or("-".into(), |v| format!("{v:.3}")),
                r.q3.map_or("-".into(), |v| format!("{v:.3}")),
                opt(Spread::of(c.nodes.clone()).median, 1.0),
                orig.as_ref().map_or_else(
                    || "-".into(),
                    |o| pct_p(
                        change(o.search_mean(), c.search_mean()),
                        &o.search_s,
                        &c.search_s
                    )
                ),
                orig.as_ref().map_or_else(
                    || "-".into(),
                    |o| pct_p(change(o.path_mean(), c.path_mean()), &o.path_m, &c.path_m)
                ),
            );
        }
        let _ = writeln!(md, "\n![box plots of {m}]({rel}/box-{m}.svg)\n");
    }
}

/// One `{{...}}` of the notes ([`fill`]): a statistic of the folder, as the notes quote it.
fn resolve_note(page: &Page<'_>, scheme_changes: &[SchemeChange], args: &[&str]) -> Result<String> {
    let Page { maps, planners, .. } = page;
    let cell = |p: &str, m: &str| page.cell(p, m);
    let [stat, measure, rest @ ..] = args else {
        anyhow::bail!("expected STAT|MEASURE|...");
    };
    if *stat == "maps" {
        // {{maps|MEASURE|PLANNER|MAP_A|MAP_B}}: medians on both maps and the
        // Mann-Whitney p of the two samples, e.g. `600 -> 300 ms (p 0.02)`.
        let [planner, a, b] = rest else {
            anyhow::bail!("expected maps|MEASURE|PLANNER|MAP_A|MAP_B");
        };
        anyhow::ensure!(
            planners.iter().any(|p| p == planner)
                && maps.iter().any(|m| m == a)
                && maps.iter().any(|m| m == b),
            "no planner {planner:?} on maps {a:?} and {b:?} in this folder"
        );
        let (ca, cb) = (cell(planner, a), cell(planner, b));
        let (sa, sb) = (ca.measure(measure)?, cb.measure(measure)?);
        let p = crate::results::stats::mann_whitney_p(sa, sb)
            .map_or(String::new(), |p| format!(" (p {p:.2})"));
        return Ok(format!(
            "{} -> {}{p}",
            show_measure(measure, Spread::of(sa.to_vec()).median),
            show_measure(measure, Spread::of(sb.to_vec()).median)
        ));
    }
    let scheme_of = |label: &str| -> Result<Scheme> {
        Ok(match label {
            "-1" => Scheme::Bidirectional,
            "-2" => Scheme::Rewiring,
            "bi" => Scheme::Both,
            _ => anyhow::bail!("scheme {label:?}: -1, -2 or bi"),
        })
    };
    if *stat == "pairs" {
        // {{pairs|MEASURE|SCHEME}}: over every planner pair of the scheme on every
        // map, how many changes of the mean are below zero, how many pairs differ outside
        // seed noise (p < 0.05), and the span of their p.
        let [label] = rest else {
            anyhow::bail!("expected pairs|MEASURE|-1, -2 or bi");
        };
        let sch = scheme_of(label)?;
        let (mut below, mut all, mut ps) = (0, 0, Vec::<f64>::new());
        for m in maps {
            for p in planners {
                let Some((s, o)) = scheme(p) else { continue };
                if s != sch || !planners.contains(&o) {
                    continue;
                }
                let (co, cp) = (cell(&o, m), cell(p, m));
                let (a, b) = (co.measure(measure)?, cp.measure(measure)?);
                if let Some(c) = change(mean(a), mean(b)) {
                    all += 1;
                    below += usize::from(c < 0.0);
                }
                ps.extend(crate::results::stats::mann_whitney_p(a, b));
            }
        }
        let lo = ps.iter().copied().reduce(f64::min).context("no pairs")?;
        let hi = ps.iter().copied().reduce(f64::max).context("no pairs")?;
        let span = if hi < 0.01 {
            "every Mann-Whitney p below 0.01".to_string()
        } else {
            format!("Mann-Whitney p {lo:.2}-{hi:.2}")
        };
        let outside = ps.iter().filter(|&&p| p < 0.05).count();
        return Ok(format!(
            "{below} of the {all} planner-map pairs below zero, {outside} with p < 0.05 ({span})"
        ));
    }
    if *stat == "scheme" {
        let [label, map] = rest else {
            anyhow::bail!("expected scheme|search, join or path|-1, -2 or bi|MAP");
        };
        let sch = scheme_of(label)?;
        let (_, _, ds, dj, dp, _) = scheme_changes
            .iter()
            .find(|(s, m, ..)| *s == sch && m == map)
            .with_context(|| format!("no scheme {label} on {map:?} in this folder"))?;
        return Ok(pct(match *measure {
            "search" => *ds,
            "join" => *dj,
            "path" => *dp,
            _ => anyhow::bail!("scheme changes are of search, join or path"),
        }));
    }
    let [planner, map] = rest else {
        anyhow::bail!("expected {stat}|{measure}|PLANNER|MAP");
    };
    anyhow::ensure!(
        (*planner == "*" || planners.iter().any(|p| p == planner)) && maps.iter().any(|m| m == map),
        "no planner {planner:?} on map {map:?} in this folder (`*`: every planner)"
    );
    let c = cell(planner, map);
    let sample = c.measure(measure)?;
    let fmt = |v: Option<f64>| show_measure(measure, v);
    match *stat {
        // {{sum|MEASURE|PLANNER|MAP}}: the sample's total (e.g. collisions);
        // {{nonzero|...}}: the runs with a value other than zero, "K of N".
        "sum" => Ok(fmt(Some(sample.iter().sum()))),
        "nonzero" => Ok(format!(
            "{} of {}",
            sample.iter().filter(|&&v| v != 0.0).count(),
            sample.len()
        )),
        "mean" => Ok(fmt(mean(sample))),
        "median" => Ok(fmt(Spread::of(sample.to_vec()).median)),
        "max" => Ok(fmt(sample.iter().copied().reduce(f64::max))),
        "change" => {
            let (_, orig) = scheme(planner)
                .filter(|(s, _)| *s != Scheme::Original)
                .with_context(|| format!("{planner} is an original planner"))?;
            let o = cell(&orig, map);
            let os = o.measure(measure)?;
            Ok(pct_p(change(mean(os), mean(sample)), os, sample))
        }
        _ => anyhow::bail!("statistic {stat:?}: sum, nonzero, mean, median, max, change or scheme"),
    }
}

/// Table 3: map processing.
fn table3(manifest: &Manifest, md: &mut String) {
    // Table 3.
    let _ = writeln!(md, "## Table 3: map processing\n");
    let _ = writeln!(
        md,
        "Measured when the folder was run (one core each). The geodesic metric here computes a \
         distance field per target on demand (Dijkstra on the grid graph) and caches it; the \
         paper's figure is for all pairs up front.\n"
    );
    let _ = writeln!(
        md,
        "| map | cells | diffusion bake (s) | table bytes | grid graph (s) | one geodesic field \
         (ms) | exact optima (ms) |\n|---|---:|---:|---:|---:|---:|---:|"
    );
    for t in &manifest.maps {
        let _ = writeln!(
            md,
            "| {} | {} x {} of {} m | {} | {} | {} | {} | {} |",
            t.scenario,
            t.cols,
            t.rows,
            t.cell_m,
            opt(t.diffusion_bake_s, 1.0),
            t.table_bytes.map_or("-".into(), |b| b.to_string()),
            num(t.graph_s),
            num(t.geodesic_field_s * 1e3),
            num(t.optima_s * 1e3)
        );
    }
}

/// Writes `out` (Markdown): each folder of `variants` (label, folder) against the folder
/// `base`, run with the same matrix and settings but for one switch each. Per planner and
/// map, over goal 1: the base's mean, and each variant's change of the mean with the
/// Mann-Whitney p of the two samples (bold below 0.05), for travelled path length, search
/// time (to the end of the joining call), the join instant and nodes at goal. Settings that differ from the base's are listed per variant.
pub fn compare(
    base: &Path,
    variants: &[(String, PathBuf)],
    out: &Path,
    command: &str,
    notes: Option<&str>,
) -> Result<()> {
    let load = |dir: &Path| -> Result<(Manifest, Vec<Row>)> {
        let m = Manifest::read(dir)?
            .with_context(|| format!("{} has no experiment.json", dir.display()))?;
        let rows = read_rows(dir, false)?
            .into_iter()
            .filter(|r| r.goal_index == 1)
            .collect();
        Ok((m, rows))
    };
    let (bm, brows) = load(base)?;
    let mut vs = Vec::new();
    for (label, dir) in variants {
        let (m, rows) = load(dir)?;
        if m.settings.planners != bm.settings.planners
            || m.settings.scenarios != bm.settings.scenarios
            || m.settings.repeats != bm.settings.repeats
            || m.settings.seed != bm.settings.seed
        {
            anyhow::bail!(
                "{} is not the same matrix as {} (planners, scenarios and seeds must match)",
                dir.display(),
                base.display()
            );
        }
        vs.push((label.clone(), m, rows));
    }
    let cell = |rows: &[Row], p: &str, m: &str| {
        let rs: Vec<&Row> = rows
            .iter()
            .filter(|r| r.planner == p && r.scenario == m)
            .collect();
        Cell::of(&rs)
    };
    let diffs = |m: &Manifest| -> String {
        let (Ok(a), Ok(b)) = (
            serde_json::to_value(&m.settings),
            serde_json::to_value(&bm.settings),
        ) else {
            return String::new();
        };
        let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
            return String::new();
        };
        let d: Vec<String> = a
            .iter()
            .filter(|(k, v)| b.get(*k) != Some(v))
            .map(|(k, v)| format!("`{k}` {v}"))
            .collect();
        if d.is_empty() {
            "none (the same settings)".into()
        } else {
            d.join(", ")
        }
    };
    let done = |rows: &[Row]| crate::results::done_runs(rows).len();
    let mut md = String::new();
    let _ = writeln!(md, "# Results: one switch at a time\n");
    let _ = writeln!(
        md,
        "Generated by `{command}` ({}). Base: `{}` ({} runs of goal 1, {} repeats from seed {}, \
         clock `{:?}`, pace `{:?}`).\n",
        bm.tool,
        base.display(),
        done(&brows),
        bm.settings.repeats,
        bm.settings.seed,
        bm.settings.clock,
        bm.settings.pace,
    );
    let _ = writeln!(
        md,
        "| variant | folder | runs | settings changed |\n|---|---|---:|---|"
    );
    for ((label, m, rows), (_, dir)) in vs.iter().zip(variants) {
        let _ = writeln!(
            md,
            "| {label} | `{}` | {} | {} |",
            dir.display(),
            done(rows),
            diffs(m)
        );
    }
    let _ = writeln!(md);
    let maps: Vec<&str> = bm
        .settings
        .scenarios
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    type Pick = fn(&Cell) -> &Vec<f64>;
    let measures: [(&str, &str, f64, Pick); 4] = [
        ("Travelled path length", "m", 1.0, |c| &c.path_m),
        (
            "Search time (to the end of the call in which the goal joined)",
            "ms",
            1e3,
            |c| &c.search_s,
        ),
        ("Join instant", "ms", 1e3, |c| &c.join_s),
        ("Nodes at goal", "nodes", 1.0, |c| &c.nodes),
    ];
    if let Some(n) = notes {
        // {{change|MEASURE|VARIANT|PLANNER|MAP}}, {{minp|MEASURE|VARIANT}} (the smallest p
        // over every planner and map, with that change), {{range|MEASURE|VARIANT}} (the
        // changes' span); MEASURE: path, search, join or nodes.
        let resolve = |args: &[&str]| -> Result<String> {
            let [stat, measure, variant, rest @ ..] = args else {
                anyhow::bail!("expected STAT|MEASURE|VARIANT|...");
            };
            let pick: Pick = match *measure {
                "path" => |c| &c.path_m,
                "search" => |c| &c.search_s,
                "join" => |c| &c.join_s,
                "nodes" => |c| &c.nodes,
                _ => anyhow::bail!("measure {measure:?}: path, search, join or nodes"),
            };
            let (_, _, vrows) = vs
                .iter()
                .find(|(l, _, _)| l == variant)
                .with_context(|| format!("no variant {variant:?}"))?;
            let one = |p: &str, m: &str| {
                let (b, v) = (cell(&brows, p, m), cell(vrows, p, m));
                let (bs, s) = (pick(&b).clone(), pick(&v).clone());
                (
                    change(mean(&bs), mean(&s)),
                    crate::results::stats::mann_whitney_p(&bs, &s),
                    bs,
                    s,
                )
            };
            let all = || {
                bm.settings
                    .planners
                    .iter()
                    .flat_map(|p| maps.iter().map(move |m| (p.clone(), *m)))
                    .map(|(p, m)| one(&p, m))
                    .collect::<Vec<_>>()
            };
            match (*stat, rest) {
                ("change", [planner, map]) => {
                    anyhow::ensure!(
                        bm.settings.planners.iter().any(|p| p == planner) && maps.contains(map),
                        "no planner {planner:?} on map {map:?}"
                    );
                    let (c, _, bs, s) = one(planner, map);
                    Ok(pct_p(c, &bs, &s))
                }
                ("minp", []) => all()
                    .into_iter()
                    .filter_map(|(c, p, _, _)| Some((p?, c?)))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(p, c)| format!("p {p:.2} ({c:+.1} %)"))
                    .context("no samples"),
                ("range", []) => {
                    let cs: Vec<f64> = all().into_iter().filter_map(|(c, ..)| c).collect();
                    let lo = cs.iter().copied().reduce(f64::min).context("no samples")?;
                    let hi = cs.iter().copied().reduce(f64::max).context("no samples")?;
                    Ok(format!("{lo:+.1} % to {hi:+.1} %"))
                }
                _ => anyhow::bail!("expected change|M|V|PLANNER|MAP, minp|M|V or range|M|V"),
            }
        };
        let filled = fill(n, resolve).context("the notes quote the data")?;
        let _ = writeln!(md, "{}\n", filled.trim_end());
    }
    for (title, unit, scale, pick) in measures {
        let _ = writeln!(
            md,
            "## {title}\n\nBase mean ({unit}) and each variant's change of the mean, with the \
             Mann-Whitney p of the two samples; **bold**: p < 0.05.\n"
        );
        let _ = write!(md, "| planner | map | base |");
        for (label, _, _) in &vs {
            let _ = write!(md, " {label} |");
        }
        let _ = write!(md, "\n|---|---|---:|");
        for _ in &vs {
            let _ = write!(md, "---:|");
        }
        let _ = writeln!(md);
        for p in &bm.settings.planners {
            for m in &maps {
                let b = cell(&brows, p, m);
                let bs = pick(&b);
                let _ = write!(md, "| {p} | {m} | {} |", opt(mean(bs), scale));
                for (_, _, rows) in &vs {
                    let v = cell(rows, p, m);
                    let s = pick(&v);
                    let c = change(mean(bs), mean(s));
                    let p = crate::results::stats::mann_whitney_p(bs, s);
                    let text = pct_p(c, bs, s);
                    if p.is_some_and(|p| p < 0.05) {
                        let _ = write!(md, " **{text}** |");
                    } else {
                        let _ = write!(md, " {text} |");
                    }
                }
                let _ = writeln!(md);
            }
        }
        let _ = writeln!(md);
    }
    if let Some(dir) = out.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(out, md).with_context(|| format!("{}", out.display()))?;
    Ok(())
}

/// The Fig. 7 section (runs of `experiment --obstacle`): per map and planner, how the disc
/// dropped on goal 1's path was handled, and a box plot of the detours.
#[allow(clippy::too_many_arguments)]
fn fig7(
    md: &mut String,
    charts: &mut Vec<PathBuf>,
    goal1: &[&Row],
    planners: &[String],
    maps: &[String],
    settings: &crate::results::Settings,
    chart_dir: &Path,
    rel: &str,
) -> Result<()> {
    let t_exp_s = settings.t_exp_ms.unwrap_or(150.0) / 1e3;
    let radius = settings.obstacle_m.unwrap_or(f32::NAN);
    let _ = writeln!(md, "## Fig. 7: a disc dropped on the path\n");
    let _ = writeln!(
        md,
        "Once the agent has moved 2 m, a disc of radius {radius} m is dropped on goal 1's \
         planned path at the first path point more than 10 m ahead (and more than the radius \
         + 3 m from the goal). *Calls to a free path*: plan calls from the drop until the \
         planner's path to the goal is free of the disc again (the simulation looks between \
         calls, so one call is the least it can see). *Replanned / before*: that path's cost \
         against the path's cost just before the drop. *Detour*: what the agent travelled \
         from the drop to the goal against the exact optimum from there around the disc \
         (the disc rasterised to cells of at most 0.25 m wholly inside it, so the optimum \
         is at most the true one and the detour at least the true one).\n"
    );
    for m in maps {
        let _ = writeln!(
            md,
            "### {m}\n\n| planner | dropped | reached | collisions | calls to a free path, \
             median [max] | never free | replanned / before, mean | detour, median [IQR] | \
             detour, mean |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|"
        );
        let mut samples = Vec::new();
        for p in planners {
            let rs: Vec<&Row> = goal1
                .iter()
                .filter(|r| &r.planner == p && &r.scenario == m)
                .copied()
                .collect();
            let dropped: Vec<&&Row> = rs.iter().filter(|r| r.disc_r_m.is_some()).collect();
            let Cell {
                replan_s, detour, ..
            } = Cell::of(&rs);
            let calls: Vec<f64> = replan_s.iter().map(|s| (s / t_exp_s).round()).collect();
            let never = dropped.iter().filter(|r| r.replan_s.is_none()).count();
            let cost: Vec<f64> = dropped
                .iter()
                .filter_map(|r| Some(f64::from(r.replanned_cost_m? / r.cost_before_drop_m?)))
                .collect();
            let c = Spread::of(calls.clone());
            let d = Spread::of(detour.clone());
            let f3 = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3}"));
            let _ = writeln!(
                md,
                "| {p} | {}/{} | {} | {} | {} [{}] | {never} | {} | {} [{}, {}] | {} |",
                dropped.len(),
                rs.len(),
                dropped.iter().filter(|r| r.reached).count(),
                dropped.iter().map(|r| r.collisions).sum::<u32>(),
                opt(c.median, 1.0),
                opt(calls.iter().copied().reduce(f64::max), 1.0),
                f3(mean(&cost)),
                f3(d.median),
                f3(d.q1),
                f3(d.q3),
                f3(mean(&detour)),
            );
            samples.push(detour);
        }
        let file = chart_dir.join(format!("fig7-{m}"));
        let boxes = Boxes {
            title: format!("Fig. 7, {m}: a disc of {radius} m dropped on the path"),
            panels: vec![BoxPanel {
                title: "travelled from the drop / exact optimum around the disc".into(),
                x_label: "ratio".into(),
                log: false,
                names: planners.to_vec(),
                samples,
            }],
        };
        if boxes.panels[0].samples.iter().any(|s| !s.is_empty()) {
            render(&boxes, &file)?;
            charts.push(file);
            let _ = writeln!(md, "\n![Fig. 7 detours on {m}]({rel}/fig7-{m}.svg)\n");
        } else {
            let _ = writeln!(md);
        }
    }
    Ok(())
}

/// Replaces every `{{A|B|...}}` in `text` with `resolve(&[A, B, ...])`: notes written by
/// hand quote the data through these, so a regenerated page never states a figure its data
/// no longer gives, and a quote the data cannot answer (a planner or map the folder does not
/// hold) is an error naming it.
pub fn fill(text: &str, resolve: impl Fn(&[&str]) -> Result<String>) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find("{{") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let j = after
            .find("}}")
            .with_context(|| format!("unclosed {{{{ at {:?}", &rest[i..rest.len().min(i + 40)]))?;
        let key = &after[..j];
        let args: Vec<&str> = key.split('|').map(str::trim).collect();
        out.push_str(&resolve(&args).with_context(|| format!("{{{{{key}}}}}"))?);
        rest = &after[j + 2..];
    }
    out.push_str(rest);
    Ok(out)
}
