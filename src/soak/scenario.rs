//! A soak scenario: a TOML parameter file naming the start-up list, the channels and what they
//! stream, the feeder's behaviour, the faults to inject, the length and the invariants.
//! Every key is checked; an unknown key or a bad range is an error naming it.

use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::bounded::BoundedReadError;
use crate::machine::plc::PlcConfig;
use crate::params::runtime::PlcSettings;

use super::feed::FeederSpec;
use super::generator::ProgramSpec;

/// Largest scenario file read.
pub(crate) const MAX_SCENARIO_BYTES: u64 = 1 << 20;

#[derive(Debug, Error)]
pub enum ScenarioError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Toml { path: String, msg: String },
    #[error("{path}: {msg}")]
    Invalid { path: String, msg: String },
}

/// When the soak is over: the first of the given limits reached.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Length {
    /// Executed stream blocks, all channels together.
    pub blocks: Option<u64>,
    pub ticks: Option<u64>,
    /// Channel time, seconds.
    pub sim_seconds: Option<f64>,
    /// Wall-clock time, seconds.
    pub wall_seconds: Option<f64>,
}

/// Faults injected at random ticks (scenario `[faults]`); every range is `[low, high]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Faults {
    /// NC reset after this many executed blocks of the channel (then the program restarts).
    pub(crate) reset_every_blocks: Option<[u64; 2]>,
    /// NC reset after this many ticks.
    pub(crate) reset_every_ticks: Option<[u64; 2]>,
    /// Feed hold every so many ticks, lasting `hold_ticks`.
    pub hold_every_ticks: Option<[u64; 2]>,
    #[serde(default = "default_hold")]
    pub(crate) hold_ticks: [u64; 2],
    /// A new feed override every so many ticks, from `override_pct`.
    pub override_every_ticks: Option<[u64; 2]>,
    #[serde(default = "default_override")]
    pub(crate) override_pct: [f64; 2],
    /// Forced rejections: the feeder's attempts are skipped for `reject_ticks`.
    pub reject_every_ticks: Option<[u64; 2]>,
    #[serde(default = "default_reject")]
    pub(crate) reject_ticks: [u64; 2],
}

impl Default for Faults {
    /// No faults.
    fn default() -> Self {
        Faults {
            reset_every_blocks: None,
            reset_every_ticks: None,
            hold_every_ticks: None,
            hold_ticks: default_hold(),
            override_every_ticks: None,
            override_pct: default_override(),
            reject_every_ticks: None,
            reject_ticks: default_reject(),
        }
    }
}

fn default_hold() -> [u64; 2] {
    [10, 100]
}
fn default_override() -> [f64; 2] {
    [50.0, 200.0]
}
fn default_reject() -> [u64; 2] {
    [5, 50]
}

/// What must hold (scenario `[invariants]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InvariantSpec {
    /// Channel error numbers that are part of the scenario (the channel is reset and goes on).
    pub(crate) expected_errors: Vec<u32>,
    /// Allowed growth of the resident set from warm-up to the end, KiB.
    pub(crate) memory_slack_kib: u64,
    /// Share of the run (by the length limit) after which the memory baseline is taken.
    pub(crate) warmup: f64,
}

impl Default for InvariantSpec {
    fn default() -> Self {
        InvariantSpec {
            expected_errors: Vec::new(),
            memory_slack_kib: 1024,
            warmup: 0.1,
        }
    }
}

/// One channel of the scenario (`[[channel]]`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSpec {
    /// 1-based channel number in the start-up list.
    pub number: u32,
    /// The program started (default: the channel's streaming program).
    pub program: Option<String>,
    /// Stream this file (relative to the scenario) instead of the generated program; it is
    /// streamed from the top again each time the program ends or is reset.
    pub file: Option<PathBuf>,
    pub feeder: Option<FeederSpec>,
    #[serde(rename = "program_mix")]
    pub(crate) program_mix: Option<ProgramSpec>,
    /// A simulated PLC answers this channel's technology functions (`[channel.plc]`, the
    /// keys of runtime.toml's `[plc]` but `channels`); absent = the channel acknowledges its
    /// own units after the process times.
    pub plc: Option<PlcSettings>,
}

/// The machine's PLC configuration of `[plc]` settings, its delays drawn from `seed`.
pub fn plc_config(s: &PlcSettings, seed: u64) -> PlcConfig {
    PlcConfig {
        delay_ms: s.delay_ms.range(),
        overrides: s.overrides(),
        late_every: s.late_every,
        late_ms: s.late_ms,
        stop_after: s.stop_after,
        seed,
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Start-up list, relative to the scenario file.
    pub params: PathBuf,
    #[serde(default)]
    pub seed: u64,
    /// "virtual" (default) or "realtime".
    #[serde(default)]
    pub(crate) clock: ClockSpec,
    pub length: Length,
    #[serde(default)]
    pub feeder: FeederSpec,
    #[serde(default)]
    pub program: ProgramSpec,
    #[serde(default)]
    pub faults: Faults,
    #[serde(default)]
    pub invariants: InvariantSpec,
    /// Channels to soak; empty = every channel of the start-up list with the defaults.
    #[serde(default, rename = "channel")]
    pub channels: Vec<ChannelSpec>,
    /// The scenario file's folder (set on load).
    #[serde(skip)]
    pub dir: PathBuf,
    #[serde(skip)]
    pub path: PathBuf,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum ClockSpec {
    #[default]
    Virtual,
    Realtime,
}

fn range_ok(r: Option<[u64; 2]>) -> bool {
    r.is_none_or(|[a, b]| 1 <= a && a <= b)
}

impl Scenario {
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let p = path.display().to_string();
        let bytes = crate::bounded::read_file(path, MAX_SCENARIO_BYTES).map_err(|e| match e {
            BoundedReadError::Io(source) => ScenarioError::Io {
                path: p.clone(),
                source,
            },
            e @ (BoundedReadError::TooLarge { .. } | BoundedReadError::NotRegular) => {
                ScenarioError::Invalid {
                    path: p.clone(),
                    msg: e.to_string(),
                }
            }
        })?;
        let text = String::from_utf8(bytes).map_err(|_| ScenarioError::Invalid {
            path: p.clone(),
            msg: "not UTF-8 text".to_string(),
        })?;
        let mut s = Scenario::parse(&text).map_err(|msg| ScenarioError::Toml {
            path: p.clone(),
            msg,
        })?;
        s.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        s.path = path.to_path_buf();
        s.validate()
            .map_err(|msg| ScenarioError::Invalid { path: p, msg })?;
        Ok(s)
    }

    /// Parse the TOML text (without validation or paths).
    pub fn parse(text: &str) -> Result<Scenario, String> {
        toml::from_str(text).map_err(|e| e.to_string().trim_end().to_string())
    }

    /// The start-up list's path.
    pub(crate) fn params_path(&self) -> PathBuf {
        self.dir.join(&self.params)
    }

    pub(crate) fn validate(&self) -> Result<(), String> {
        let l = &self.length;
        if l.blocks.is_none()
            && l.ticks.is_none()
            && l.sim_seconds.is_none()
            && l.wall_seconds.is_none()
        {
            return Err("[length] needs blocks, ticks, sim_seconds or wall_seconds".into());
        }
        for (name, v) in [
            ("sim_seconds", l.sim_seconds),
            ("wall_seconds", l.wall_seconds),
        ] {
            if v.is_some_and(|s| !(s.is_finite() && s > 0.0 && s <= 1e7)) {
                return Err(format!("[length] {name} must be in (0, 1e7]"));
            }
        }
        self.feeder.check()?;
        self.program.check()?;
        let f = &self.faults;
        for (name, r) in [
            ("reset_every_blocks", f.reset_every_blocks),
            ("reset_every_ticks", f.reset_every_ticks),
            ("hold_every_ticks", f.hold_every_ticks),
            ("override_every_ticks", f.override_every_ticks),
            ("reject_every_ticks", f.reject_every_ticks),
            ("hold_ticks", Some(f.hold_ticks)),
            ("reject_ticks", Some(f.reject_ticks)),
        ] {
            if !range_ok(r) {
                return Err(format!(
                    "[faults] {name} must be [low, high] with 1 <= low <= high"
                ));
            }
        }
        let [o0, o1] = f.override_pct;
        if !(0.0 <= o0 && o0 <= o1 && o1 <= 200.0) {
            return Err("[faults] override_pct must be [low, high] within 0..=200".into());
        }
        let inv = &self.invariants;
        if !(inv.warmup.is_finite() && (0.0..1.0).contains(&inv.warmup)) {
            return Err("[invariants] warmup must be in [0, 1)".into());
        }
        let mut seen = Vec::new();
        for c in &self.channels {
            if c.number == 0 || seen.contains(&c.number) {
                return Err(format!(
                    "[[channel]] number {}: channels are numbered from 1, each once",
                    c.number
                ));
            }
            seen.push(c.number);
            if let Some(fs) = &c.feeder {
                fs.check()?;
            }
            if let Some(ps) = &c.program_mix {
                ps.check()?;
            }
            if let Some(plc) = &c.plc {
                if plc.channels.is_some() {
                    return Err(format!(
                        "[[channel]] number {}: plc.channels: not a scenario key (the PLC plays for its [[channel]])",
                        c.number
                    ));
                }
                plc.check().map_err(|(key, why)| {
                    format!("[[channel]] number {}: plc.{key}: {why}", c.number)
                })?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimal_scenario_parses_with_defaults() {
        let s = Scenario::parse("params = \"startup.lis\"\n[length]\nblocks = 10\n").unwrap();
        s.validate().unwrap();
        assert_eq!(s.length.blocks, Some(10));
        assert_eq!(s.feeder, FeederSpec::default());
        assert_eq!(s.clock, ClockSpec::Virtual);
    }

    #[test]
    fn unknown_keys_and_bad_ranges_are_errors() {
        let e = Scenario::parse("params = \"a\"\nlenght = 3\n[length]\nblocks = 1\n").unwrap_err();
        assert!(e.contains("lenght"), "{e}");
        let s = Scenario::parse(
            "params = \"a\"\n[length]\nblocks = 1\n[faults]\nhold_every_ticks = [5, 2]\n",
        )
        .unwrap();
        assert!(s.validate().unwrap_err().contains("hold_every_ticks"));
        let s = Scenario::parse("params = \"a\"\n[length]\n").unwrap();
        assert!(s.validate().is_err());
        let s = Scenario::parse(
            "params = \"a\"\n[length]\nticks = 1\n[feeder]\npacket_bytes = [10, 2000]\n",
        )
        .unwrap();
        assert!(s.validate().unwrap_err().contains("packet_bytes"));
    }

    #[test]
    fn a_channel_plc_is_read_and_its_bad_keys_named() {
        let head = "params = \"a\"\n[length]\nticks = 1\n[[channel]]\nnumber = 1\n[channel.plc]\n";
        let s = Scenario::parse(&format!(
            "{head}delay_ms = [10, 20]\nfunctions = {{ M8 = 300, S = [1, 2] }}\nlate_every = 3\nlate_ms = 50\nstop_after = 9\n"
        ))
        .unwrap();
        s.validate().unwrap();
        let c = plc_config(s.channels[0].plc.as_ref().unwrap(), 7);
        assert_eq!(c.delay_ms, [10, 20]);
        assert_eq!(
            c.delay_of(crate::vocab::techno::TechnoKind::M, 8),
            [300, 300]
        );
        assert_eq!(
            (c.late_every, c.late_ms, c.stop_after, c.seed),
            (Some(3), 50, Some(9), 7)
        );
        for (bad, key) in [
            ("delay_ms = [20, 10]", "plc.delay_ms"),
            ("functions = { Q8 = 1 }", "plc.functions.Q8"),
            ("functions = { M8 = [5, 1] }", "plc.functions.M8"),
            ("late_every = 0", "plc.late_every"),
        ] {
            let s = Scenario::parse(&format!("{head}{bad}\n")).unwrap();
            let e = s.validate().unwrap_err();
            assert!(e.contains(key), "{bad}: {e}");
        }
        let e = Scenario::parse(&format!("{head}delay = 5\n")).unwrap_err();
        assert!(e.contains("delay"), "{e}");
        let e = Scenario::parse(&format!("{head}delay_ms = \"x\"\n")).unwrap_err();
        assert!(e.contains("a delay in ms"), "{e}");
    }
}
