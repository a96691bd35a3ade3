//! `runtime.toml`: what the emulator needs that controller lists do not hold (cycle period,
//! axis limits, decoder and planner budgets, simulated file-system latency, ADS endpoint).
//! Every key has a default; an unknown key is an error naming it.

use std::net::SocketAddr;
use std::path::Path;

use serde::Deserialize;

use crate::diag::Diagnostic;
// NetIds and route entries are the floor's, shared with the ADS server: one parser, one meaning.
use crate::vocab::ams::{AmsNetId, RouteEntry};
use crate::vocab::axis::{AXIS_LETTERS, MAX_AXES};

/// Largest runtime.toml we read; the real one is a few KiB.
pub(crate) const MAX_RUNTIME_BYTES: u64 = 1024 * 1024;

/// The emulator's own settings.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RuntimeConfig {
    /// Period of the fixed-cycle loop in µs (default 1000 = 1 ms, the usual CNC cycle).
    pub cycle_period_us: u64,
    /// The CNC's working directory, which relative paths in the lists are joined to; relative
    /// to runtime.toml's folder. Default: the start-up list's folder, or its parent when that
    /// folder is called `listen` (an installation's layout).
    pub cnc_dir: Option<std::path::PathBuf>,
    /// Simulated latency of every program file open in µs (default 0), so soak tests can
    /// show what the file cache saves.
    pub fs_latency_us: u64,
    /// Additional simulated read latency per KiB in µs (default 0).
    pub fs_latency_us_per_kib: u64,
    /// The channel's axes (default X, Y, Z with the limits of [`AxisConfig`]'s defaults).
    pub axes: Vec<AxisConfig>,
    pub decoder: DecoderRuntime,
    pub planner: PlannerConfig,
    pub ads: AdsConfig,
    /// A simulated PLC answering the technology functions (`[plc]`); absent = none, the
    /// channel acknowledges its own units after the functions' process times.
    pub plc: Option<PlcSettings>,
    /// The runtime thread's real-time mode (`[realtime]`; default off), README "Real-time mode".
    pub realtime: crate::vocab::realtime::RealtimeConfig,
}

impl Default for RuntimeConfig {
    fn default() -> Self {
        RuntimeConfig {
            cycle_period_us: 1000,
            cnc_dir: None,
            fs_latency_us: 0,
            fs_latency_us_per_kib: 0,
            axes: ["X", "Y", "Z"]
                .iter()
                .map(|n| AxisConfig::named(n))
                .collect(),
            decoder: DecoderRuntime::default(),
            planner: PlannerConfig::default(),
            ads: AdsConfig::default(),
            plc: None,
            realtime: crate::vocab::realtime::RealtimeConfig::default(),
        }
    }
}

/// Whether an axis moves along a line (mm) or turns (degrees: every `_mm` limit of a rotary
/// axis is in °, every `_mm_per_…` in °/…). From an axis list's `kenngr.achs_typ`
/// (P-AXIS-00018); axes written in runtime.toml are linear.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum AxisKind {
    #[default]
    Linear,
    Rotary,
}

/// One axis's name and limits: the one axis table motion, the 21897 limit check and the
/// ADS axis objects read, filled from the axis lists or from runtime.toml.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisConfig {
    /// Axis name as programmed: one of `X Y Z A B C` (the axes the interpolator drives).
    /// Required.
    pub name: String,
    /// Linear or rotary (not a runtime.toml key: only axis lists say so).
    #[serde(skip)]
    pub kind: AxisKind,
    /// Largest programmed feed in mm/min (default 30000).
    #[serde(default = "default_velocity")]
    pub max_velocity_mm_per_min: f64,
    /// Largest acceleration in mm/s² (default 2000).
    #[serde(default = "default_acceleration")]
    pub max_acceleration_mm_per_s2: f64,
    /// Largest jerk in mm/s³; absent = no jerk limit (default absent).
    #[serde(default)]
    pub max_jerk_mm_per_s3: Option<f64>,
    /// Rapid traverse (G0) rate in mm/min (default 30000); not above max velocity.
    #[serde(default = "default_velocity")]
    pub rapid_mm_per_min: f64,
    /// Lower software limit in mm (default -1000).
    #[serde(default = "default_soft_min")]
    pub soft_limit_min_mm: f64,
    /// Upper software limit in mm (default 1000).
    #[serde(default = "default_soft_max")]
    pub soft_limit_max_mm: f64,
}

fn default_velocity() -> f64 {
    30000.0
}
fn default_acceleration() -> f64 {
    2000.0
}
fn default_soft_min() -> f64 {
    -1000.0
}
fn default_soft_max() -> f64 {
    1000.0
}

impl AxisConfig {
    /// An axis with the default limits.
    pub fn named(name: &str) -> Self {
        AxisConfig {
            name: name.to_string(),
            kind: AxisKind::Linear,
            max_velocity_mm_per_min: default_velocity(),
            max_acceleration_mm_per_s2: default_acceleration(),
            max_jerk_mm_per_s3: None,
            rapid_mm_per_min: default_velocity(),
            soft_limit_min_mm: default_soft_min(),
            soft_limit_max_mm: default_soft_max(),
        }
    }
}

/// Is `name` an axis name ncchannel drives: a letter X Y Z A B C U V W, then at most 15
/// letters, digits or `_` (`lang::block::AxisName`)?
pub(crate) fn is_axis_name(name: &str) -> bool {
    crate::lang::block::AxisName::new(name.trim()).is_some()
}

/// The interpolator's index (`AXIS_LETTERS`) an axis name such as `x`, `Z` or `X1` claims: the
/// slot of its first letter X Y Z A B C. `None` for U V W (and `U1`…), which take a slot no
/// name claims ([`channel_slots`]), and for a name that is no axis name. Two axes claiming one
/// slot (`X` and `X1`) are refused where the axes are listed.
pub(crate) fn axis_index(name: &str) -> Option<usize> {
    let n = crate::lang::block::AxisName::new(name.trim())?;
    AXIS_LETTERS.iter().position(|&l| l == n.letter())
}

/// The slot of each of a channel's axes, in list order: the one its name claims
/// ([`axis_index`]), or for a U, V or W the first slot, in `AXIS_LETTERS` order, that no name
/// of the list claims and no earlier U V W took (TF5200 channel parameters, P-CHAN-00006:
/// the axis names are the channel list's). `None` for a name that is no axis name or when
/// no slot is left. The one rule `setup` and the validation share.
pub(crate) fn channel_slots<'a>(
    names: impl Iterator<Item = &'a str> + Clone,
) -> Vec<Option<usize>> {
    let mut taken = [false; AXIS_LETTERS.len()];
    for i in names.clone().filter_map(axis_index) {
        taken[i] = true;
    }
    names
        .map(|n| {
            if !is_axis_name(n) {
                return None;
            }
            axis_index(n).or_else(|| {
                let free = taken.iter().position(|t| !t)?;
                taken[free] = true;
                Some(free)
            })
        })
        .collect()
}

/// Decoder budgets.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DecoderRuntime {
    /// Most NC blocks decoded in one tick (default 64), so a long program cannot stall a cycle.
    pub blocks_per_tick: u32,
    /// Decoded blocks held between decoder and planner (default 8).
    pub buffer_blocks: u32,
    /// Deepest subroutine nesting (default 20).
    pub max_subroutine_depth: u32,
}

impl Default for DecoderRuntime {
    fn default() -> Self {
        DecoderRuntime {
            blocks_per_tick: 64,
            buffer_blocks: 8,
            max_subroutine_depth: 20,
        }
    }
}

/// Motion planner settings.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlannerConfig {
    /// Motion blocks the planner looks ahead over (default 32).
    pub lookahead_blocks: u32,
    /// Corner smoothing window in ms (default 0 = off): a moving average over the axis
    /// positions that spreads each junction's velocity jump over this time, so corners of fine
    /// polylines keep speed while every axis keeps its acceleration limit (docs/motion.md).
    pub(crate) corner_smoothing_ms: f64,
}

impl Default for PlannerConfig {
    fn default() -> Self {
        PlannerConfig {
            lookahead_blocks: 32,
            corner_smoothing_ms: 0.0,
        }
    }
}

/// The ADS server endpoint.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdsConfig {
    /// TCP address to listen on (default 127.0.0.1:48898, the ADS port, local only).
    pub bind: SocketAddrText,
    /// Our AMS NetId (default 127.0.0.2.1.1, `vocab::ams::DEFAULT_NET_ID` says why).
    pub net_id: AmsNetId,
    /// Largest AMS/TCP frame accepted, in bytes (default 65536).
    pub max_frame_bytes: u32,
    /// Clients allowed to connect: AMS NetIds or IP addresses (default empty = everyone).
    pub allowed_clients: Vec<RouteEntry>,
    /// Simultaneous connections (default 64); more are closed at once.
    pub max_connections: u32,
    /// Notification handles per connection (default 256); more are answered 0x716.
    pub(crate) max_notifications_per_connection: u32,
    /// Notification handles, all connections together (default 1024).
    pub(crate) max_notifications_total: u32,
    /// Notification samples per second, all connections together (default 40000); at least
    /// `notification_samples_per_s_per_connection`.
    pub(crate) notification_samples_per_s: u32,
    /// Notification samples per second of one connection (default 10000, ten 1 ms handles);
    /// a handle beyond it is refused 0x716 to that connection only.
    pub(crate) notification_samples_per_s_per_connection: u32,
    /// Seconds without a whole frame after which a connection in the middle of a frame, or
    /// without notification handles, is closed (default 60).
    pub(crate) idle_timeout_s: u32,
    /// Milliseconds a request waits for the runtime before it is answered 0x708 "busy, not
    /// applied" (default 500); must stay below the clients' request timeouts (README).
    pub reply_timeout_ms: u32,
}

impl AdsConfig {
    /// `reply_timeout_ms` as the time a request waits for the runtime.
    pub fn reply_timeout(&self) -> std::time::Duration {
        std::time::Duration::from_millis(u64::from(self.reply_timeout_ms))
    }
}

impl Default for AdsConfig {
    /// The ADS server's own defaults (`vocab::ams`, which `ads::server` uses too), so each
    /// limit has one number.
    fn default() -> Self {
        use crate::vocab::ams;
        AdsConfig {
            bind: SocketAddrText(ams::DEFAULT_BIND),
            net_id: ams::DEFAULT_NET_ID,
            max_frame_bytes: ams::DEFAULT_MAX_FRAME_BYTES as u32,
            allowed_clients: Vec::new(),
            max_connections: ams::DEFAULT_MAX_CONNECTIONS as u32,
            max_notifications_per_connection: ams::DEFAULT_MAX_NOTIFICATIONS as u32,
            max_notifications_total: ams::DEFAULT_MAX_NOTIFICATIONS_TOTAL as u32,
            notification_samples_per_s: ams::DEFAULT_NOTIFICATION_SAMPLES_PER_S as u32,
            notification_samples_per_s_per_connection:
                ams::DEFAULT_NOTIFICATION_SAMPLES_PER_S_PER_CONNECTION as u32,
            idle_timeout_s: ams::DEFAULT_IDLE_TIMEOUT.as_secs() as u32,
            reply_timeout_ms: ams::DEFAULT_REPLY_TIMEOUT.as_millis() as u32,
        }
    }
}

/// The simulated PLC (`machine::plc`): runtime.toml's `[plc]` and a soak scenario's
/// `[channel.plc]`. Delays are channel time, ms.
#[derive(Debug, Clone, PartialEq, Eq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlcSettings {
    /// The channels it plays for (runtime.toml; default: every channel).
    #[serde(default)]
    pub channels: Option<Vec<u32>>,
    /// Delay of a function `functions` does not name: ms, or `[min, max]` drawn by `seed`.
    #[serde(default)]
    pub delay_ms: PlcDelay,
    /// Delays by function: `"M8"`, `"H7"`, `"M"` (every M), `"S"`, `"T"`, `"T5"`.
    #[serde(default)]
    pub functions: std::collections::BTreeMap<String, PlcDelay>,
    /// Every `late_every`-th acknowledgement comes `late_ms` later.
    #[serde(default)]
    pub late_every: Option<u64>,
    #[serde(default)]
    pub late_ms: u64,
    /// After this many acknowledgements the PLC answers no more.
    #[serde(default)]
    pub stop_after: Option<u64>,
    /// Seed of the drawn delays.
    #[serde(default)]
    pub seed: u64,
}

/// A delay in ms: fixed, or a range drawn from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(
    untagged,
    expecting = "a delay in ms: a number, or [min, max] with min <= max"
)]
pub enum PlcDelay {
    Fixed(u64),
    Range([u64; 2]),
}

impl Default for PlcDelay {
    fn default() -> Self {
        PlcDelay::Fixed(0)
    }
}

/// Longest PLC delay accepted, ms (an hour).
const MAX_PLC_DELAY_MS: u64 = 3_600_000;

impl PlcDelay {
    /// `[min, max]` (a fixed delay is `[n, n]`).
    pub fn range(self) -> [u64; 2] {
        match self {
            PlcDelay::Fixed(n) => [n, n],
            PlcDelay::Range(r) => r,
        }
    }

    fn check(self) -> Result<(), String> {
        let [a, b] = self.range();
        if a > b {
            return Err(format!("[{a}, {b}]: min is above max"));
        }
        if b > MAX_PLC_DELAY_MS {
            return Err(format!("{b} ms is more than {MAX_PLC_DELAY_MS} ms"));
        }
        Ok(())
    }
}

/// A function key of `[plc] functions`: `M8` → (M, Some(8)), `S` → (S, None).
pub fn plc_function_key(key: &str) -> Option<(crate::vocab::techno::TechnoKind, Option<u32>)> {
    use crate::vocab::techno::TechnoKind;
    let mut chars = key.chars();
    let kind = match chars.next()?.to_ascii_uppercase() {
        'M' => TechnoKind::M,
        'H' => TechnoKind::H,
        'S' => TechnoKind::S,
        'T' => TechnoKind::T,
        _ => return None,
    };
    let rest = chars.as_str();
    if rest.is_empty() {
        return Some((kind, None));
    }
    if kind == TechnoKind::S || !rest.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    rest.parse().ok().map(|n| (kind, Some(n)))
}

impl PlcSettings {
    /// Check every key; the error names it (`delay_ms`, `functions.M8`, …) and says why.
    pub fn check(&self) -> Result<(), (String, String)> {
        if let Some(ch) = &self.channels {
            if ch.contains(&0) {
                return Err(("channels".into(), "channels are numbered from 1".into()));
            }
        }
        self.delay_ms.check().map_err(|e| ("delay_ms".into(), e))?;
        for (k, d) in &self.functions {
            if plc_function_key(k).is_none() {
                return Err((
                    format!("functions.{k}"),
                    format!("`{k}` is not a function: M<n>, H<n>, T<n>, or M, H, S, T for all"),
                ));
            }
            d.check().map_err(|e| (format!("functions.{k}"), e))?;
        }
        if self.late_every == Some(0) {
            return Err(("late_every".into(), "must be at least 1".into()));
        }
        if self.late_ms > MAX_PLC_DELAY_MS {
            return Err((
                "late_ms".into(),
                format!("{} ms is more than {MAX_PLC_DELAY_MS} ms", self.late_ms),
            ));
        }
        Ok(())
    }

    /// The per-function delays, kind, number (`None`: the kind's every number) and range;
    /// keys that are not functions are left out (`check` refuses them).
    pub fn overrides(&self) -> Vec<(crate::vocab::techno::TechnoKind, Option<u32>, [u64; 2])> {
        self.functions
            .iter()
            .filter_map(|(k, d)| plc_function_key(k).map(|(kind, n)| (kind, n, d.range())))
            .collect()
    }
}

/// A socket address read from a string, with an error message that says what is expected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(try_from = "String")]
pub struct SocketAddrText(pub SocketAddr);

impl TryFrom<String> for SocketAddrText {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
            .map(SocketAddrText)
            .map_err(|_| format!("`{s}` is not an address:port such as 127.0.0.1:48898"))
    }
}

/// Parse and check runtime.toml text. Errors name the key (`ads.net_id`, `axes[1].name`).
pub(crate) fn parse_runtime(file: &Path, text: &str) -> Result<RuntimeConfig, Vec<Diagnostic>> {
    let cfg: RuntimeConfig = toml::from_str(text).map_err(|e| vec![toml_error(file, text, &e)])?;
    let errs = validate(&cfg, file, text);
    if errs.is_empty() {
        Ok(cfg)
    } else {
        Err(errs)
    }
}

/// Read runtime.toml with the size bound, then parse and check it.
pub(crate) fn read_runtime(file: &Path) -> Result<RuntimeConfig, Vec<Diagnostic>> {
    use crate::bounded::{read_file, BoundedReadError};
    let err = |m: String| vec![Diagnostic::error(file, 1, 1, None, m)];
    let bytes = read_file(file, MAX_RUNTIME_BYTES).map_err(|e| {
        err(match e {
            BoundedReadError::TooLarge { bytes, limit } => {
                format!("runtime.toml is {bytes} bytes, more than the limit of {limit} bytes")
            }
            BoundedReadError::Io(e) => format!("cannot read runtime.toml: {e}"),
            e @ BoundedReadError::NotRegular => format!("runtime.toml is {e}"),
        })
    })?;
    let text = String::from_utf8(bytes)
        .map_err(|e| err(format!("cannot read runtime.toml: {}", e.utf8_error())))?;
    parse_runtime(file, &text)
}

/// A toml error as a diagnostic at its span, prefixed with the dotted key it concerns.
fn toml_error(file: &Path, text: &str, e: &toml::de::Error) -> Diagnostic {
    let msg = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return Diagnostic::error(file, 1, 1, None, msg);
    };
    let (line, col) = line_col(text, span.start);
    let line_text = text.lines().nth(line - 1).unwrap_or("");
    let key = Spans::parse(text).and_then(|s| s.key_at(span.start));
    let message = match key {
        Some(k) if !msg.contains(&format!("`{k}`")) => format!("{k}: {msg}"),
        _ => msg,
    };
    Diagnostic::error(file, line, col, None, message).with_source(line_text)
}

/// 1-based line and character column of byte offset `off`.
fn line_col(text: &str, off: usize) -> (usize, usize) {
    let off = off.min(text.len());
    let before = text.get(..off).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before.get(line_start..).map_or(0, |s| s.chars().count()) + 1;
    (line, col)
}

/// Where things are written in runtime.toml: the spans `toml_edit` (the parser under `toml`)
/// keeps for every key, value and table header, so a diagnostic points at the text itself.
struct Spans<'a> {
    doc: toml_edit::ImDocument<&'a str>,
}

impl<'a> Spans<'a> {
    fn parse(text: &'a str) -> Option<Self> {
        toml_edit::ImDocument::parse(text)
            .ok()
            .map(|doc| Spans { doc })
    }

    /// The table `table` (entry `index` of an array of tables); `""` is the root.
    fn table(&self, table: &str, index: Option<usize>) -> Option<&toml_edit::Table> {
        let root = self.doc.as_table();
        if table.is_empty() {
            return Some(root);
        }
        match (root.get(table)?, index) {
            (item, Some(i)) => item.as_array_of_tables()?.get(i),
            (item, None) => item.as_table(),
        }
    }

    /// Byte offset of `key` in its table; a key left at its default points at its table's
    /// header; `None` when the table is not written either.
    fn offset_of(&self, table: &str, index: Option<usize>, key: &str) -> Option<usize> {
        let t = self.table(table, index)?;
        t.key(key)
            .and_then(|k| k.span())
            .or_else(|| t.span())
            .map(|r| r.start)
    }

    /// The dotted key whose value holds byte `offset`: `ads.net_id`, `axes[1].name`.
    fn key_at(&self, offset: usize) -> Option<String> {
        let holds = |item: &toml_edit::Item| item.span().is_some_and(|r| r.contains(&offset));
        let in_table = |t: &toml_edit::Table, prefix: &str| {
            t.iter()
                .find(|(_, v)| holds(v))
                .map(|(k, _)| format!("{prefix}{k}"))
        };
        let root = self.doc.as_table();
        for (name, item) in root.iter() {
            if let Some(t) = item.as_table() {
                if let Some(k) = in_table(t, &format!("{name}.")) {
                    return Some(k);
                }
            } else if let Some(a) = item.as_array_of_tables() {
                for (i, t) in a.iter().enumerate() {
                    if let Some(k) = in_table(t, &format!("{name}[{i}].")) {
                        return Some(k);
                    }
                }
            } else if holds(item) {
                return Some(name.to_string());
            }
        }
        None
    }
}

fn join_key(table: &str, index: Option<usize>, key: &str) -> String {
    match (table.is_empty(), index) {
        (true, _) => key.to_string(),
        (false, Some(i)) => format!("{table}[{i}].{key}"),
        (false, None) => format!("{table}.{key}"),
    }
}

fn validate(cfg: &RuntimeConfig, file: &Path, text: &str) -> Vec<Diagnostic> {
    let mut errs = Vec::new();
    let spans = Spans::parse(text);
    let mut fail = |table: &str, index: Option<usize>, key: &str, why: String| {
        let (line, col, src) = match spans.as_ref().and_then(|s| s.offset_of(table, index, key)) {
            Some(off) => {
                let (line, col) = line_col(text, off);
                let src = text.lines().nth(line - 1).unwrap_or("").to_string();
                (line, col, src)
            }
            None => (1, 1, String::new()),
        };
        let mut d = Diagnostic::error(
            file,
            line,
            col,
            None,
            format!("{}: {why}", join_key(table, index, key)),
        );
        if !src.is_empty() {
            d = d.with_source(&src);
        }
        errs.push(d);
    };

    validate_timing(cfg, &mut fail);
    validate_axes(cfg, &mut fail);
    validate_decoder_planner(cfg, &mut fail);
    validate_ads(cfg, &mut fail);
    if let Err((key, why)) = cfg.realtime.check() {
        fail("realtime", None, key, why);
    }
    if let Some(Err((key, why))) = cfg.plc.as_ref().map(PlcSettings::check) {
        let (key, sub) = match key.split_once('.') {
            Some((k, sub)) => (k.to_string(), format!("{sub}: {why}")),
            None => (key, why),
        };
        fail("plc", None, &key, sub);
    }
    errs
}

/// Validation step 1: the cycle period and the simulated file-system latencies.
fn validate_timing(cfg: &RuntimeConfig, fail: &mut impl FnMut(&str, Option<usize>, &str, String)) {
    if cfg.cycle_period_us == 0 || cfg.cycle_period_us > 1_000_000 {
        fail(
            "",
            None,
            "cycle_period_us",
            format!("{} µs is not in 1 ... 1000000", cfg.cycle_period_us),
        );
    }
    for (key, v) in [
        ("fs_latency_us", cfg.fs_latency_us),
        ("fs_latency_us_per_kib", cfg.fs_latency_us_per_kib),
    ] {
        if v > 10_000_000 {
            fail("", None, key, format!("{v} µs is more than 10 s"));
        }
    }
}

/// Validation step 2: the axis count, then each axis ([`validate_axis`]).
fn validate_axes(cfg: &RuntimeConfig, fail: &mut impl FnMut(&str, Option<usize>, &str, String)) {
    if cfg.axes.is_empty() || cfg.axes.len() > MAX_AXES {
        fail(
            "",
            None,
            "axes",
            format!("{} axes; 1 ... {MAX_AXES} are needed", cfg.axes.len()),
        );
    }
    for (i, a) in cfg.axes.iter().enumerate().take(MAX_AXES) {
        validate_axis(cfg, i, a, fail);
    }
}

/// Validation step 2, per axis: its name, uniqueness, limits of motion and soft limits.
fn validate_axis(
    cfg: &RuntimeConfig,
    i: usize,
    a: &AxisConfig,
    fail: &mut impl FnMut(&str, Option<usize>, &str, String),
) {
    let at = Some(i);
    if !is_axis_name(&a.name) {
        fail(
            "axes",
            at,
            "name",
            format!(
                "`{}` is not an axis name ncchannel drives (X Y Z A B C U V W, or one of them followed by at most 15 letters, digits or `_`, as `X1`)",
                a.name
            ),
        );
    }
    if cfg.axes[..i].iter().any(|b| {
        b.name.eq_ignore_ascii_case(&a.name)
            || axis_index(&b.name).is_some() && axis_index(&b.name) == axis_index(&a.name)
    }) {
        fail(
            "axes",
            at,
            "name",
            format!("axis `{}` is defined twice", a.name),
        );
    }
    let positive = [
        ("max_velocity_mm_per_min", Some(a.max_velocity_mm_per_min)),
        (
            "max_acceleration_mm_per_s2",
            Some(a.max_acceleration_mm_per_s2),
        ),
        ("max_jerk_mm_per_s3", a.max_jerk_mm_per_s3),
        ("rapid_mm_per_min", Some(a.rapid_mm_per_min)),
    ];
    for (key, v) in positive {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                fail("axes", at, key, format!("{v} must be a positive number"));
            }
        }
    }
    if a.max_velocity_mm_per_min > 0.0 && a.rapid_mm_per_min > a.max_velocity_mm_per_min {
        fail(
            "axes",
            at,
            "rapid_mm_per_min",
            format!(
                "{} mm/min is above max_velocity_mm_per_min {}",
                a.rapid_mm_per_min, a.max_velocity_mm_per_min
            ),
        );
    }
    if !(a.soft_limit_min_mm.is_finite() && a.soft_limit_max_mm.is_finite())
        || a.soft_limit_min_mm >= a.soft_limit_max_mm
    {
        fail(
            "axes",
            at,
            "soft_limit_max_mm",
            format!(
                "soft limits {} ... {} mm: min must be below max",
                a.soft_limit_min_mm, a.soft_limit_max_mm
            ),
        );
    }
}

/// Validation step 3: decoder and planner sizes.
fn validate_decoder_planner(
    cfg: &RuntimeConfig,
    fail: &mut impl FnMut(&str, Option<usize>, &str, String),
) {
    for (key, v, max) in [
        ("blocks_per_tick", cfg.decoder.blocks_per_tick, 1_000_000),
        ("buffer_blocks", cfg.decoder.buffer_blocks, 1_000_000),
        (
            "max_subroutine_depth",
            cfg.decoder.max_subroutine_depth,
            1000,
        ),
    ] {
        if v == 0 || v > max {
            fail("decoder", None, key, format!("{v} is not in 1 ... {max}"));
        }
    }
    let la = cfg.planner.lookahead_blocks;
    if la == 0 || la > 100_000 {
        fail(
            "planner",
            None,
            "lookahead_blocks",
            format!("{la} is not in 1 ... 100000"),
        );
    }
    let cs = cfg.planner.corner_smoothing_ms;
    if !(cs.is_finite() && (0.0..=1000.0).contains(&cs)) {
        fail(
            "planner",
            None,
            "corner_smoothing_ms",
            format!("{cs} is not in 0 ... 1000"),
        );
    }
}

/// Validation step 4: the ADS server's frame size, connection and notification limits.
fn validate_ads(cfg: &RuntimeConfig, fail: &mut impl FnMut(&str, Option<usize>, &str, String)) {
    let fb = cfg.ads.max_frame_bytes;
    // An AMS/TCP header (6) plus an AMS header (32) must fit; 16 MiB bounds one allocation.
    if !(64..=16 * 1024 * 1024).contains(&fb) {
        fail(
            "ads",
            None,
            "max_frame_bytes",
            format!("{fb} is not in 64 ... 16777216"),
        );
    }
    for (key, v, max) in [
        ("max_connections", cfg.ads.max_connections, 1024),
        (
            "max_notifications_per_connection",
            cfg.ads.max_notifications_per_connection,
            4096,
        ),
        (
            "max_notifications_total",
            cfg.ads.max_notifications_total,
            65_536,
        ),
        (
            "notification_samples_per_s",
            cfg.ads.notification_samples_per_s,
            1_000_000,
        ),
        (
            "notification_samples_per_s_per_connection",
            cfg.ads.notification_samples_per_s_per_connection,
            1_000_000,
        ),
        ("idle_timeout_s", cfg.ads.idle_timeout_s, 86_400),
        ("reply_timeout_ms", cfg.ads.reply_timeout_ms, 60_000),
    ] {
        if !(1..=max).contains(&v) {
            fail("ads", None, key, format!("{v} is not in 1 ... {max}"));
        }
    }
    // One connection's budget is part of the server's: a total below it could never be met.
    let (per, total) = (
        cfg.ads.notification_samples_per_s_per_connection,
        cfg.ads.notification_samples_per_s,
    );
    if per > total {
        fail(
            "ads",
            None,
            "notification_samples_per_s_per_connection",
            format!("{per} is above notification_samples_per_s ({total})"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn net_id_parses_and_prints() {
        let id: AmsNetId = "192.168.0.10.1.1".parse().unwrap();
        assert_eq!(id.0, [192, 168, 0, 10, 1, 1]);
        assert_eq!(id.to_string(), "192.168.0.10.1.1");
        assert!("1.2.3.4.5".parse::<AmsNetId>().is_err());
        assert!("1.2.3.4.5.6.7".parse::<AmsNetId>().is_err());
        assert!("1.2.3.4.5.256".parse::<AmsNetId>().is_err());
        assert!("1.2.3.4.5.+6".parse::<AmsNetId>().is_err());
    }

    #[test]
    fn empty_text_is_the_defaults() {
        let cfg = parse_runtime(Path::new("r.toml"), "").unwrap();
        assert_eq!(cfg, RuntimeConfig::default());
        assert_eq!(cfg.axes.len(), 3);
    }

    #[test]
    fn realtime_keys_are_read_and_checked() {
        use crate::vocab::realtime::Policy;
        let text = "[realtime]\npolicy = \"rr\"\npriority = 80\ncpu = 1\nlock_memory = true\nrequired = true\n";
        let rt = parse_runtime(Path::new("r.toml"), text).unwrap().realtime;
        assert_eq!(rt.policy, Policy::Rr);
        assert_eq!(
            (rt.priority, rt.cpu, rt.lock_memory, rt.required),
            (Some(80), Some(1), true, true)
        );
        let errs = parse_runtime(Path::new("r.toml"), "[realtime]\npriority = 0\n").unwrap_err();
        assert!(
            errs[0]
                .message
                .starts_with("realtime.priority: 0 is not in 1 ... 99"),
            "{}",
            errs[0].message
        );
        assert_eq!(errs[0].line, 2);
        let errs =
            parse_runtime(Path::new("r.toml"), "[realtime]\npolicy = \"idle\"\n").unwrap_err();
        assert!(
            errs[0].message.contains("realtime.policy"),
            "{}",
            errs[0].message
        );
    }

    #[test]
    fn error_names_key_in_array_table() {
        let text =
            "[[axes]]\nname = \"X\"\n\n[[axes]]\nname = \"Y\"\nmax_velocity_mm_per_min = -5.0\n";
        let errs = parse_runtime(Path::new("r.toml"), text).unwrap_err();
        assert_eq!(errs.len(), 1, "{errs:?}");
        assert!(
            errs[0]
                .message
                .starts_with("axes[1].max_velocity_mm_per_min:"),
            "{}",
            errs[0].message
        );
        assert_eq!((errs[0].line, errs[0].col), (6, 1));
    }

    #[test]
    fn notification_budgets_are_keys_and_one_connection_fits_in_the_total() {
        let text = "[ads]\nnotification_samples_per_s = 20000\nnotification_samples_per_s_per_connection = 5000\n";
        let cfg = parse_runtime(Path::new("r.toml"), text).unwrap();
        assert_eq!(cfg.ads.notification_samples_per_s, 20_000);
        assert_eq!(cfg.ads.notification_samples_per_s_per_connection, 5_000);
        let text = "[ads]\nnotification_samples_per_s = 20000\nnotification_samples_per_s_per_connection = 20001\n";
        let errs = parse_runtime(Path::new("r.toml"), text).unwrap_err();
        assert_eq!(errs.len(), 1, "{errs:?}");
        assert!(
            errs[0].message.starts_with(
                "ads.notification_samples_per_s_per_connection: 20001 is above notification_samples_per_s (20000)"
            ),
            "{}",
            errs[0].message
        );
        let text = "[ads]\nnotification_samples_per_s_per_connection = 0\n";
        let errs = parse_runtime(Path::new("r.toml"), text).unwrap_err();
        assert!(
            errs[0].message.contains("0 is not in 1 ... 1000000"),
            "{errs:?}"
        );
    }

    #[test]
    fn type_error_names_key() {
        let errs = parse_runtime(Path::new("r.toml"), "[ads]\nmax_frame_bytes = -1\n").unwrap_err();
        assert!(
            errs[0].message.starts_with("ads.max_frame_bytes:"),
            "{}",
            errs[0].message
        );
        assert_eq!(errs[0].line, 2);
        let errs = parse_runtime(Path::new("r.toml"), "[ads]\nnet_id = \"1.2.3\"\n").unwrap_err();
        assert!(
            errs[0].message.contains("ads.net_id"),
            "{}",
            errs[0].message
        );
        assert!(errs[0].message.contains("AMS NetId"), "{}", errs[0].message);
    }

    #[test]
    fn routes_take_net_ids_and_ips() {
        let cfg = parse_runtime(
            Path::new("r.toml"),
            "[ads]\nallowed_clients = [\"10.0.0.5\", \"10.0.0.5.1.1\", \"::1\"]\n",
        )
        .unwrap();
        assert_eq!(cfg.ads.allowed_clients.len(), 3);
        assert!(matches!(cfg.ads.allowed_clients[1], RouteEntry::NetId(_)));
        assert!(
            parse_runtime(Path::new("r.toml"), "[ads]\nallowed_clients = [\"foo\"]\n").is_err()
        );
    }

    #[test]
    fn diagnostics_point_at_the_key_where_it_is_written() {
        let text = "cycle_period_us = 1000\n\n[[axes]]\nname = \"X\"\n\n[[axes]]\n  name = \"Q\"\n\n[decoder]\nx = 1\nblocks_per_tick = 0\n";
        let errs = parse_runtime(Path::new("r.toml"), text).unwrap_err();
        // `x` is an unknown key: a toml error at its own place, named with its table.
        assert_eq!((errs[0].line, errs[0].col), (10, 1), "{errs:?}");
        assert!(errs[0].message.contains("x"), "{errs:?}");
        let text = "cycle_period_us = 1000\n\n[[axes]]\nname = \"X\"\n\n[[axes]]\n  name = \"Q\"\n\n[decoder]\nblocks_per_tick = 0\n";
        let errs = parse_runtime(Path::new("r.toml"), text).unwrap_err();
        let at: Vec<(usize, usize, &str)> = errs
            .iter()
            .map(|d| (d.line, d.col, d.message.split(':').next().unwrap_or("")))
            .collect();
        assert!(at.contains(&(7, 3, "axes[1].name")), "{at:?}");
        assert!(at.contains(&(10, 1, "decoder.blocks_per_tick")), "{at:?}");
    }
}
