//! A soak campaign: every scenario with each of a run of seeds, run whole on one machine or as
//! shard I of N on N machines (`soak --shard I/N`), and the campaign report that `soak merge`
//! joins into one verdict. An existing engine (a Kubernetes Indexed Job, a CI matrix) starts
//! the shards; ncchannel only splits the campaign and merges the reports (docs/campaigns.md).

use std::collections::BTreeSet;
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::report::{RunStatus, SoakReport};

/// Shards a campaign may be cut into at most (a bound on the merge's bookkeeping).
pub const MAX_SHARDS: u32 = 100_000;
/// Runs a campaign may have at most (scenarios × seeds).
pub const MAX_RUNS: u64 = 10_000_000;

/// Shard `index` of `count`, 1-based: runs `index - 1`, `index - 1 + count`, … of the
/// campaign. Round robin over the runs in campaign order (scenario by scenario, seed by seed),
/// so each shard gets its share of every scenario and the shards take about as long.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The whole campaign as one shard.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Does run `run` (0-based, campaign order) belong to this shard?
    pub fn holds(self, run: u64) -> bool {
        run % u64::from(self.count) == u64::from(self.index - 1)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// `I/N` with 1 ≤ I ≤ N ≤ [`MAX_SHARDS`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("'{s}' is not I/N with 1 <= I <= N <= {MAX_SHARDS}");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count || count > MAX_SHARDS {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// What a campaign is: its scenarios (as named on the command line) and seeds. Every shard of
/// one campaign carries the same spec; merge refuses reports of different campaigns.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CampaignSpec {
    pub scenarios: Vec<String>,
    /// The first seed of every scenario (`--seed`); `None`: each scenario's own `seed`.
    pub first_seed: Option<u64>,
    /// Seeds per scenario: first, first + 1, … (`--seeds`).
    pub seeds: u64,
    /// Runs of the whole campaign: scenarios × seeds.
    pub runs: u64,
}

/// One run of a campaign: which scenario (by its place in the spec) with which seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunPlan {
    /// Place in campaign order, 0-based.
    pub index: u64,
    pub scenario: usize,
    pub seed: u64,
}

impl CampaignSpec {
    /// The spec of `scenarios` × `seeds` seeds; an empty or oversized campaign is refused.
    pub fn new(
        scenarios: Vec<String>,
        first_seed: Option<u64>,
        seeds: u64,
    ) -> Result<Self, String> {
        let runs = (scenarios.len() as u64)
            .checked_mul(seeds)
            .filter(|&r| r > 0 && r <= MAX_RUNS)
            .ok_or_else(|| {
                format!(
                    "{} scenario(s) × {seeds} seed(s): a campaign has 1 to {MAX_RUNS} runs",
                    scenarios.len()
                )
            })?;
        Ok(CampaignSpec {
            scenarios,
            first_seed,
            seeds,
            runs,
        })
    }

    /// The runs of `shard`, in campaign order; `own_seed(i)` is scenario i's own seed.
    pub fn plan(&self, shard: Shard, own_seed: impl Fn(usize) -> u64) -> Vec<RunPlan> {
        let seeds = self.seeds.max(1);
        (u64::from(shard.index - 1)..self.runs)
            .step_by(shard.count as usize)
            .map(|index| {
                let scenario = (index / seeds) as usize;
                let first = self.first_seed.unwrap_or_else(|| own_seed(scenario));
                RunPlan {
                    index,
                    scenario,
                    seed: first.wrapping_add(index % seeds),
                }
            })
            .collect()
    }
}

/// One finished run in a campaign report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignRun {
    /// Place in campaign order, 0-based.
    pub index: u64,
    pub report: SoakReport,
}

/// The report of a campaign, a shard of one, or several shards merged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignReport {
    /// Complete (every planned run ran), interrupted by a signal, or the placeholder written
    /// when the shard started; merge takes complete reports only.
    pub status: RunStatus,
    /// The campaign run this report belongs to (`soak --run-id`): every shard of one run of a
    /// campaign carries the same; merge refuses a report of another (a stale one).
    pub run_id: Option<String>,
    pub campaign: CampaignSpec,
    /// The shards this report covers (one for a shard's own report), all of one count.
    pub shards: Vec<Shard>,
    /// Every run of the covered shards finished and held every invariant.
    pub all_held: bool,
    /// The covered shards' runs, in campaign order.
    pub runs: Vec<CampaignRun>,
}

#[derive(Debug, Error)]
pub enum MergeError {
    #[error("no report to merge")]
    Empty,
    #[error("{0} is of another campaign than {1} (scenarios, seeds and runs differ)")]
    OtherCampaign(String, String),
    #[error("{0} cuts the campaign into {1} shards, {2} into {3}")]
    OtherCount(String, u32, String, u32),
    #[error("shard {shard} is in {first} and in {second}")]
    Twice {
        shard: Shard,
        first: String,
        second: String,
    },
    #[error("shard(s) {0} missing: the campaign is not complete")]
    Missing(String),
    #[error("{0}: the shard never finished (its run was killed, or is still running): no verdict from it")]
    Incomplete(String),
    #[error("{0}: the shard was interrupted (SIGINT/SIGTERM) after {1} of its runs: run it again")]
    Interrupted(String, usize),
    #[error("{name} is stale: it is of campaign run {found}, not {wanted} (give every shard of one run the same --run-id)")]
    Stale {
        name: String,
        found: String,
        wanted: String,
    },
    #[error("{name}: run {index} {why}")]
    BadRun {
        name: String,
        index: u64,
        why: &'static str,
    },
}

impl CampaignReport {
    /// The report of `shard`'s finished `runs` (fewer than planned when the run was stopped:
    /// then it does not hold).
    pub fn new(
        campaign: CampaignSpec,
        shard: Shard,
        planned: usize,
        runs: Vec<CampaignRun>,
    ) -> Self {
        let complete =
            runs.len() == planned && runs.iter().all(|r| r.report.status == RunStatus::Complete);
        let all_held = complete && runs.iter().all(|r| r.report.all_held);
        CampaignReport {
            status: if complete {
                RunStatus::Complete
            } else {
                RunStatus::Interrupted
            },
            run_id: None,
            campaign,
            shards: vec![shard],
            all_held,
            runs,
        }
    }

    /// The placeholder a shard writes to its report file when it starts: no runs, no
    /// verdict, until the finished report replaces it.
    pub fn incomplete(campaign: CampaignSpec, shard: Shard) -> Self {
        CampaignReport {
            status: RunStatus::Incomplete,
            run_id: None,
            campaign,
            shards: vec![shard],
            all_held: false,
            runs: Vec::new(),
        }
    }

    /// The same report, of campaign run `run_id`.
    pub fn with_run_id(mut self, run_id: Option<String>) -> Self {
        self.run_id = run_id;
        self
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    /// One line per run and the verdict, for people.
    pub fn print_human(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let c = &self.campaign;
        let shards: Vec<String> = self.shards.iter().map(Shard::to_string).collect();
        writeln!(
            w,
            "campaign: {} scenario(s) × {} seed(s) = {} runs; shard(s) {}: {} run(s) here",
            c.scenarios.len(),
            c.seeds,
            c.runs,
            shards.join(" "),
            self.runs.len()
        )?;
        for r in &self.runs {
            let mark = if r.report.all_held {
                "held    "
            } else {
                "VIOLATED"
            };
            writeln!(
                w,
                "{mark}  run {} {} seed {}: {} blocks, {} ticks",
                r.index, r.report.scenario, r.report.seed, r.report.blocks, r.report.ticks
            )?;
        }
        let violated = self.runs.iter().filter(|r| !r.report.all_held).count();
        writeln!(
            w,
            "result:   {}{}",
            self.status.verdict_prefix(),
            if self.all_held {
                "every invariant held in every run".to_string()
            } else if violated > 0 {
                format!("{violated} run(s) violated an invariant")
            } else if self.status == RunStatus::Incomplete {
                "no verdict (the shard never finished)".to_string()
            } else {
                "runs are missing (stopped early)".to_string()
            }
        )
    }
}

/// Join shard reports (`name`, report) into the report of the whole campaign: all of one
/// campaign and one shard count, every shard exactly once, each shard's runs exactly the runs
/// the shard plans. Holds when every run held.
pub fn merge(
    reports: Vec<(String, CampaignReport)>,
    run_id: Option<&str>,
) -> Result<CampaignReport, MergeError> {
    let Some((first_name, first)) = reports.first() else {
        return Err(MergeError::Empty);
    };
    // The run every report must be of: the one asked for, else the first report's.
    let wanted = run_id.map(str::to_string).or_else(|| first.run_id.clone());
    let campaign = first.campaign.clone();
    let count = first.shards.first().map_or(1, |s| s.count);
    let mut seen: Vec<(Shard, &str)> = Vec::new();
    let mut runs = Vec::new();
    let mut all_held = true;
    for (name, r) in &reports {
        match r.status {
            RunStatus::Complete => {}
            RunStatus::Incomplete => return Err(MergeError::Incomplete(name.clone())),
            RunStatus::Interrupted => {
                return Err(MergeError::Interrupted(name.clone(), r.runs.len()))
            }
        }
        if r.run_id != wanted {
            let shown = |id: &Option<String>| id.clone().unwrap_or_else(|| "(none)".into());
            return Err(MergeError::Stale {
                name: name.clone(),
                found: shown(&r.run_id),
                wanted: shown(&wanted),
            });
        }
        if r.campaign != campaign {
            return Err(MergeError::OtherCampaign(name.clone(), first_name.clone()));
        }
        for &s in &r.shards {
            if s.count != count {
                return Err(MergeError::OtherCount(
                    name.clone(),
                    s.count,
                    first_name.clone(),
                    count,
                ));
            }
            if let Some((_, other)) = seen.iter().find(|(t, _)| *t == s) {
                return Err(MergeError::Twice {
                    shard: s,
                    first: (*other).to_string(),
                    second: name.clone(),
                });
            }
            seen.push((s, name));
        }
        check_runs(name, r)?;
        all_held &= r.all_held;
        runs.extend(r.runs.iter().cloned());
    }
    let have: BTreeSet<u32> = seen.iter().map(|(s, _)| s.index).collect();
    let missing: Vec<String> = (1..=count)
        .filter(|i| !have.contains(i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing(missing.join(" ")));
    }
    runs.sort_by_key(|r| r.index);
    let mut shards: Vec<Shard> = seen.into_iter().map(|(s, _)| s).collect();
    shards.sort();
    Ok(CampaignReport {
        status: RunStatus::Complete,
        run_id: wanted,
        campaign,
        shards,
        all_held,
        runs,
    })
}

/// A report's runs are runs of its shards, each once, and in range.
fn check_runs(name: &str, r: &CampaignReport) -> Result<(), MergeError> {
    let mut indices = BTreeSet::new();
    for run in &r.runs {
        let why = if run.index >= r.campaign.runs {
            Some("is beyond the campaign")
        } else if !r.shards.iter().any(|s| s.holds(run.index)) {
            Some("belongs to none of the report's shards")
        } else if !indices.insert(run.index) {
            Some("appears twice")
        } else {
            None
        };
        if let Some(why) = why {
            return Err(MergeError::BadRun {
                name: name.to_string(),
                index: run.index,
                why,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(scenarios: usize, seeds: u64) -> CampaignSpec {
        let names = (0..scenarios).map(|i| format!("s{i}.toml")).collect();
        CampaignSpec::new(names, None, seeds).unwrap()
    }

    #[test]
    fn shards_partition_the_campaign() {
        let c = spec(3, 7);
        let whole: Vec<RunPlan> = c.plan(Shard::WHOLE, |i| 100 * i as u64);
        assert_eq!(whole.len(), 21);
        assert_eq!((whole[8].scenario, whole[8].seed), (1, 101));
        for n in [1, 2, 4, 21, 30] {
            let mut union: Vec<RunPlan> = (1..=n)
                .flat_map(|i| c.plan(Shard { index: i, count: n }, |i| 100 * i as u64))
                .collect();
            assert_eq!(union.len(), whole.len(), "{n} shards: disjoint");
            union.sort_by_key(|r| r.index);
            assert_eq!(union, whole, "{n} shards: union is the campaign");
        }
    }

    #[test]
    fn shard_syntax() {
        assert_eq!("2/5".parse::<Shard>(), Ok(Shard { index: 2, count: 5 }));
        for bad in ["0/3", "4/3", "1", "a/b", "1/0", "1/1000001"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    fn report_of(c: &CampaignSpec, shard: Shard, held: impl Fn(u64) -> bool) -> CampaignReport {
        let plan = c.plan(shard, |_| 0);
        let runs: Vec<CampaignRun> = plan
            .iter()
            .map(|p| CampaignRun {
                index: p.index,
                report: SoakReport {
                    seed: p.seed,
                    all_held: held(p.index),
                    ..SoakReport::default()
                },
            })
            .collect();
        CampaignReport::new(c.clone(), shard, plan.len(), runs)
    }

    #[test]
    fn merge_needs_every_shard_once_and_holds_when_every_run_held() {
        let c = spec(2, 3);
        let shard = |i| Shard { index: i, count: 3 };
        let named = |i: u32, r| (format!("r{i}.json"), r);
        let all = |held: &dyn Fn(u64) -> bool| {
            (1..=3)
                .map(|i| named(i, report_of(&c, shard(i), held)))
                .collect::<Vec<_>>()
        };
        let merged = merge(all(&|_| true), None).unwrap();
        assert!(merged.all_held);
        assert_eq!(merged.runs.len(), 6);
        assert!(merged.runs.windows(2).all(|w| w[0].index < w[1].index));
        assert!(
            !merge(all(&|i| i != 4), None).unwrap().all_held,
            "a failing run fails the merge"
        );
        let mut two = all(&|_| true);
        two.remove(1);
        assert!(matches!(merge(two, None), Err(MergeError::Missing(m)) if m == "2/3"));
        let mut dup = all(&|_| true);
        dup.push(dup[0].clone());
        assert!(matches!(merge(dup, None), Err(MergeError::Twice { .. })));
        let mut other = all(&|_| true);
        other[2].1.campaign.seeds = 4;
        assert!(matches!(
            merge(other, None),
            Err(MergeError::OtherCampaign(..))
        ));
        // A merged report merges again, alone.
        assert_eq!(merge(vec![named(0, merged.clone())], None).unwrap(), merged);
        // An incomplete or interrupted shard, or one of another campaign run: no verdict.
        let mut killed = all(&|_| true);
        killed[1].1 = CampaignReport::incomplete(c.clone(), shard(2));
        assert!(matches!(merge(killed, None), Err(MergeError::Incomplete(n)) if n == "r2.json"));
        let mut stopped = all(&|_| true);
        stopped[2].1.runs.pop();
        stopped[2].1 = CampaignReport::new(c.clone(), shard(3), 2, stopped[2].1.runs.clone());
        assert!(matches!(
            merge(stopped, None),
            Err(MergeError::Interrupted(..))
        ));
        let of_run = |id: &str| {
            all(&|_| true)
                .into_iter()
                .map(|(n, r)| (n, r.with_run_id(Some(id.into()))))
                .collect::<Vec<_>>()
        };
        assert!(merge(of_run("42"), Some("42")).is_ok());
        assert!(matches!(
            merge(of_run("41"), Some("42")),
            Err(MergeError::Stale { .. })
        ));
        let mut mixed = of_run("42");
        mixed[2].1.run_id = Some("41".into());
        assert!(
            matches!(merge(mixed, None), Err(MergeError::Stale { name, .. }) if name == "r3.json")
        );
    }
}
