//! Planners as the commands name them, one syntax for every command ([`parse_variants`]):
//! `tuned` (the default), `paper`, `all`, Table 1 names, and the `@field=value` overrides; a run's configuration in three steps (the named
//! planner, its lengths fitted to the map, the overrides as written: [`Variant::config_for`]).

use anyhow::{Context, Result, anyhow, bail};
use bi_am_rrt::{Config, Named};

use crate::sim::Prepared;

/// The default of every command's `--planners`: the tuned Bi-AM-RRT*(D).
pub const DEFAULT_PLANNERS: &str = "tuned";

/// One planner word: `tuned` (the tuned Bi-AM-RRT*(D), `Config::default()`), `paper` (the
/// paper's Bi-AM-RRT*(D), `Config::paper()`), `all` (Table 1's 20, the paper's) or a Table 1
/// name (any case, optionally with the suffix ` tuned`).
fn named(word: &str) -> Result<Vec<Named>> {
    let word = word.trim();
    if word.eq_ignore_ascii_case("all") {
        return Ok(Named::table1().to_vec());
    }
    if word.eq_ignore_ascii_case("tuned") {
        return Ok(vec![Named::default()]);
    }
    if word.eq_ignore_ascii_case("paper") {
        return Ok(vec![Named::default().paper()]);
    }
    // Any case: `bi-am-rrt*(d)` is `Bi-AM-RRT*(D)`.
    let found = Named::table1()
        .into_iter()
        .chain(Named::table1().map(Named::tuned))
        .find(|c| c.name().to_string().eq_ignore_ascii_case(word));
    let found = found.with_context(|| {
        let all: Vec<String> = Named::table1()
            .iter()
            .map(|c| c.name().to_string())
            .collect();
        format!(
            "unknown planner {word:?}: `tuned`, `paper`, `all` or a Table 1 name ({}, each \
             also with the suffix \" tuned\")",
            all.join(", ")
        )
    })?;
    Ok(vec![found])
}

/// Planners without overrides ([`parse_variants`] with none allowed), for the studies that
/// take named planners only.
pub fn parse_planners(spec: &str) -> Result<Vec<Named>> {
    parse_variants(spec)?
        .into_iter()
        .map(|v| {
            if v.overrides.is_empty() {
                Ok(v.named)
            } else {
                bail!(
                    "{}: this command takes planner names without @overrides",
                    v.name
                )
            }
        })
        .collect()
}

/// `none`, `all`, or switch names of [`bi_am_rrt::AsPrinted::NAMES`] joined by `,` or `+`.
pub fn parse_as_printed(spec: &str) -> Result<bi_am_rrt::AsPrinted> {
    let spec = spec.trim();
    if spec.eq_ignore_ascii_case("all") {
        return Ok(bi_am_rrt::AsPrinted::ALL);
    }
    let mut out = bi_am_rrt::AsPrinted::NONE;
    if spec.eq_ignore_ascii_case("none") || spec.is_empty() {
        return Ok(out);
    }
    for name in spec.split([',', '+']) {
        if !out.set(name.trim(), true) {
            bail!(
                "unknown part {name:?} of Algorithms 4 and 6; the parts are {} (or all, none)",
                bi_am_rrt::AsPrinted::NAMES.join(", ")
            );
        }
    }
    Ok(out)
}

/// The names of the switches that are on, in [`bi_am_rrt::AsPrinted::NAMES`]'s order.
pub fn as_printed_names(p: bi_am_rrt::AsPrinted) -> Vec<String> {
    bi_am_rrt::AsPrinted::NAMES
        .iter()
        .filter(|n| {
            let mut q = p;
            q.set(n, false);
            q != p
        })
        .map(|n| n.to_string())
        .collect()
}

/// A planner as a command names it: a Table 1 name and the fields set by hand.
#[derive(Clone, Debug)]
pub struct Variant {
    /// The name in the output.
    pub name: String,
    /// The named planner with the overrides applied as written (lengths not fitted to any
    /// map): its name, metric and switches; a run's configuration is
    /// [`Variant::config_for`].
    pub cfg: Named,
    /// The named planner, before the overrides.
    pub named: Named,
    /// The overrides (`field`, `value`), in the order written.
    pub overrides: Vec<(String, String)>,
}

impl Variant {
    /// The configuration a run on `prep` gets, in three explicit steps: the named
    /// configuration, its lengths fitted to the map ([`Prepared::config`]: Table 2's with
    /// `paper_lengths`, and the scenario's `sigma`), then the overrides as written (a length
    /// set by hand is that many metres, whatever the named value).
    pub fn config_for(&self, prep: &Prepared) -> Result<Named> {
        let cfg = self.overridden(prep.config(self.named.cfg))?;
        cfg.validate()
            .map_err(|e| anyhow!("{} on {}: {e}", self.name, prep.scenario.name))?;
        Ok(Named {
            metric: self.named.metric,
            cfg,
        })
    }

    /// Changes the named configuration (a command's flags: before the overrides, so an
    /// override of the same value wins) and recomputes [`Variant::cfg`] from it.
    pub fn edit_named(&mut self, edit: impl FnOnce(&mut Config)) -> Result<()> {
        edit(&mut self.named.cfg);
        self.cfg.cfg = self.overridden(self.named.cfg)?;
        Ok(())
    }

    /// `cfg` with the overrides applied, in the order written.
    fn overridden(&self, mut cfg: Config) -> Result<Config> {
        for (k, v) in &self.overrides {
            apply(&mut cfg, k, v).with_context(|| format!("override {k}={v}"))?;
        }
        Ok(cfg)
    }
}

/// The one syntax of every command's planners: comma-separated items, each a planner word
/// (`tuned`, the default; `paper`; `all`, Table 1's 20; or a Table 1 name in any case, with
/// or without the suffix ` tuned`) optionally followed by overrides `@field=value` (any
/// value of the parameter table, [`apply`]; on `all`, on each of the 20), e.g.
/// `tuned@e_max=8,paper`: what-if variants in one run.
pub fn parse_variants(spec: &str) -> Result<Vec<Variant>> {
    let mut out = Vec::new();
    for item in spec.split(',') {
        let mut parts = item.trim().split('@');
        let word = parts.next().unwrap_or_default();
        if word.trim().is_empty() {
            bail!("empty planner name in {spec:?}");
        }
        let mut overrides = Vec::new();
        for o in parts {
            let (k, v) = o
                .split_once('=')
                .ok_or_else(|| anyhow!("override {o:?}: write field=value"))?;
            overrides.push((k.trim().to_string(), v.trim().to_string()));
        }
        let label = item.trim().split_once('@').map(|x| x.1);
        for named in named(word)? {
            let mut v = Variant {
                name: String::new(),
                cfg: named,
                named,
                overrides: overrides.clone(),
            };
            v.edit_named(|_| {})?;
            v.cfg.cfg.validate().map_err(|e| anyhow!("{item}: {e}"))?;
            v.name = match label {
                Some(l) => format!("{}@{l}", v.cfg.name()),
                None => v.cfg.name().to_string(),
            };
            out.push(v);
        }
    }
    Ok(out)
}

/// One `field=value` override: any value of the core's parameter table
/// (`bi_am_rrt::config::PARAMS`, `host-sim params` lists them), or one of two shorthands:
/// `as_printed=LIST` (the `--as-printed` switches at once) and `profile=paper|tuned` (every
/// tactic off or on).
pub fn apply(cfg: &mut Config, field: &str, v: &str) -> Result<()> {
    match field {
        "as_printed" => cfg.as_printed = parse_as_printed(v)?,
        "profile" => {
            cfg.tactics = match v {
                "paper" => bi_am_rrt::Tactics::NONE,
                "tuned" => bi_am_rrt::Tactics::TUNED,
                _ => return Err(anyhow!("profile {v:?}: paper or tuned")),
            }
        }
        "rewire_while_searching" => {
            return Err(anyhow!(
                "\"rewire_while_searching\" is now the tactic \"rewire_after_join\", the other \
                 way round (`@rewire_after_join=false` rewires while searching)"
            ));
        }
        _ => bi_am_rrt::config::set(cfg, field, v).map_err(|e| match e {
            bi_am_rrt::config::SetError::Unknown => {
                anyhow!("unknown field {field:?} (`host-sim params` lists them)")
            }
            e => anyhow!("{field} = {v:?}: {e}"),
        })?,
    }
    Ok(())
}

/// The configuration reference (`docs/reference/configuration.md`, `host-sim params`): every value of
/// the core's parameter table by group, with its unit, rule, the paper's and the tuned
/// Bi-AM-RRT*(D)'s value and its line of doc, as Markdown.
pub fn reference() -> String {
    use std::fmt::Write as _;
    let paper = Config::paper();
    let tuned = Config::default();
    let mut out = String::from(
        "# Configuration reference\n\n\
         Generated by `host-sim params` from the core's parameter table \
         (`bi_am_rrt::config::PARAMS`, `src/config/params.rs`); a test checks this page \
         against it. Every value here can be set on any planner a command takes, \
         `NAME@field=value` (several: `NAME@a=1@b=2`), and a results folder records each \
         planner's values. `Config::validate` checks each against its rule.\n\n\
         The columns give the paper's Bi-AM-RRT*(D) (`Config::paper()`, Table 2) and the \
         tuned one (`Config::default()`), before their lengths are fitted to a map \
         (`Config::for_map`: `e_max`, `e_search`, `root_step` and `sigma` scale with maps \
         outside 100-200 m across). RT-RRT*'s named sets differ in `t_root` 3, `t_goal` 3 \
         and `n_max` 12 (Table 2). Durations are in milliseconds.\n\n\
         Two shorthands besides: `@profile=paper` or `@profile=tuned` turns every tactic \
         off or on, and `@as_printed=LIST` sets the `as_printed` group as `--as-printed` \
         does.\n",
    );
    let mut group = "";
    for p in bi_am_rrt::config::PARAMS {
        if p.group != group {
            group = p.group;
            let _ = write!(
                out,
                "\n## {group}\n\n| value | unit | rule | paper | tuned | what it does |\n\
                 |---|---|---|---|---|---|\n"
            );
        }
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} | {} | {} |",
            p.name,
            p.unit,
            p.rule.text(),
            p.get(&paper),
            p.get(&tuned),
            p.doc.replace('|', "\\|")
        );
    }
    out
}

/// The one planner `spec` names ([`parse_variants`]); an error when it names none or several.
pub fn one(spec: &str) -> Result<Variant> {
    let mut all = parse_variants(spec)?;
    match all.len() {
        1 => Ok(all.remove(0)),
        n => bail!("one planner wanted; {spec:?} names {n}"),
    }
}
