//! What one update of the live view says about the runtime and each channel, as the page
//! reads it (JSON): built from a channel's [`Status`] off the runtime's thread.

use std::sync::Arc;

use serde::Serialize;

use crate::machine::Status;
use crate::vocab::mode::{Mode, State};
use crate::vocab::stats::LiveCycleReading;
use crate::vocab::techno::TechnoKind;

/// One axis of the DRO.
#[derive(Debug, Clone, Serialize)]
pub struct AxisView {
    pub axis: char,
    /// Machine coordinates, mm (rotary: degrees).
    pub mcs_mm: f64,
    /// Programming coordinates (after G54…G59), mm.
    pub pcs_mm: f64,
}

/// An error as the page lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ErrorView {
    /// 0 = the first error the channel raised.
    pub index: u64,
    /// ISG error number.
    pub code: u32,
    pub text: String,
    /// Program and 1-based line the error is about, where the channel knows them.
    pub program: Option<String>,
    pub line: Option<u64>,
}

/// One channel in one update.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelView {
    pub ch: u16,
    pub mode: Mode,
    pub state: State,
    pub axes: Vec<AxisView>,
    pub distance_to_go_mm: f64,
    pub feed_mm_per_min: f64,
    pub velocity_mm_per_s: f64,
    pub override_pct: f64,
    /// The main program running, if any.
    pub program: Option<String>,
    /// The program the executing block is in (a subroutine's name inside a call).
    pub block_program: Option<String>,
    /// 1-based line of the executing block in the listing, when the listing has its text.
    pub line: Option<usize>,
    pub block_counter: u64,
    pub block_n: Option<u32>,
    pub stream_used_bytes: usize,
    pub stream_free_bytes: usize,
    pub blocks: u64,
    pub errors_total: u64,
    pub last_error: Option<ErrorView>,
    pub message: Option<String>,
    pub techno: TechnoView,
    /// The executing motion block's programmed feed, mm/min (`None` between moves), and
    /// whether it is a rapid; `feed_mm_per_min` is the decoder's, ahead by the lookahead.
    pub executing_feed_mm_per_min: Option<f64>,
    pub executing_rapid: bool,
    /// As the executed M3/M4/M5 and S left it (as decoded before any has run).
    pub spindle: SpindleView,
    /// Tool (T) as the executed T left it (as decoded before), and the tool data set (D)
    /// as decoded.
    pub tool: u32,
    pub tool_offset: u32,
    /// The decoder's modal G codes: motion, plane, dimensions, units, feed mode, radius
    /// compensation, zero offset (`G53` for none).
    pub g_codes: Vec<&'static str>,
    /// The active zero offset's values for X Y Z, mm (0 under G53).
    pub work_offset_mm: [f64; 3],
    /// Channel time since the present program started, s (to its end once it stopped).
    pub elapsed_s: Option<f64>,
    /// Estimated time left, s: the elapsed time scaled by the share of the program's bytes
    /// still to execute (file programs only).
    pub remaining_s: Option<f64>,
    /// Stream writes refused for a full buffer (11012) since the channel was built.
    pub stream_refused_full: u64,
}

/// The spindle: M3 / M4 / M5 and the programmed speed.
#[derive(Debug, Clone, Serialize)]
pub struct SpindleView {
    /// `cw` (M3), `ccw` (M4) or `off` (M5).
    pub direction: &'static str,
    pub rpm: f64,
}

/// What the feed knows from the channel's live record (`machine::live`): the program's
/// times and the spindle and tool the executed functions set.
#[derive(Debug, Clone, Copy, Default)]
pub struct Recorded {
    pub elapsed_s: Option<f64>,
    pub remaining_s: Option<f64>,
    pub executed: crate::machine::live::Executed,
}

/// The HLI technology interface of one channel (README "Technology functions: the PLC half").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TechnoView {
    /// A PLC has set `plc_present_w`; else the channel acknowledges its own units once the
    /// function's process time has passed.
    pub plc_present: bool,
    /// Functions output to the units and acknowledged since the channel was built.
    pub output: u64,
    pub acknowledged: u64,
    /// The units holding a function the PLC has not acknowledged yet, oldest output first.
    pub waiting: Vec<WaitingUnit>,
}

/// One unit waiting for the PLC.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WaitingUnit {
    /// As programmed: `M25`, `M200=1200`, `H7=2`, `S12000`, `T2`.
    pub function: String,
    /// The synchronisation type (`MVS_SVS`, …).
    pub sync: &'static str,
    /// `std` (`techno_unit_std_sync`) or `late` (`techno_unit_late_sync`).
    pub set: &'static str,
    pub unit: usize,
    /// `please_rw` still TRUE: the PLC has not fetched it.
    pub please: bool,
    /// Channel time of the output, s, and how long it has waited since, s.
    pub output_at_s: f64,
    pub waited_s: f64,
    /// The process time the channel list gives it, µs (what the channel waits without a PLC).
    pub process_time_us: u32,
    /// Program line of the block that output it.
    pub line: u32,
}

/// The function as programmed (README "Technology functions": the value of `M200=1200` is
/// the unit's `add_value`; S carries the speed, T the tool number).
fn function_text(kind: TechnoKind, number: u32, add_value: i32) -> String {
    match kind {
        TechnoKind::S => format!("S{add_value}"),
        TechnoKind::T => format!("T{number}"),
        TechnoKind::M | TechnoKind::H if add_value != 0 => {
            format!("{}{number}={add_value}", kind.letter())
        }
        TechnoKind::M | TechnoKind::H => format!("{}{number}", kind.letter()),
    }
}

/// The technology panel: only the units the status marks open are encoded (none while the
/// channel has nothing out to the PLC).
pub fn techno_view(s: &Status) -> TechnoView {
    // Channel time of the tick that served the status: `index × period` (src/vocab/tick.rs).
    let now_ns = s.period.as_nanos().saturating_mul(u128::from(s.tick));
    let now = std::time::Duration::from_nanos(u64::try_from(now_ns).unwrap_or(u64::MAX));
    let unit = |late: bool, i: usize| {
        if late {
            s.techno.late.get(i).map(|u| (u, "late"))
        } else {
            s.techno.std.get(i).map(|u| (u, "std"))
        }
    };
    let mut waiting: Vec<WaitingUnit> = s
        .techno_open
        .units
        .iter()
        .filter_map(|&(late, i)| {
            let (u, set) = unit(late, i)?;
            let f = u.function.as_ref()?;
            Some(WaitingUnit {
                function: function_text(f.kind, f.number, f.add_value),
                sync: f.sync.name(),
                set,
                unit: i,
                please: u.please,
                output_at_s: f.output_at.as_secs_f64(),
                waited_s: now.saturating_sub(f.output_at).as_secs_f64(),
                process_time_us: f.process_time_us,
                line: f.line,
            })
        })
        .collect();
    waiting.sort_by(|a, b| a.output_at_s.total_cmp(&b.output_at_s));
    TechnoView {
        plc_present: s.techno.plc_present,
        output: s.techno_open.stats.output,
        acknowledged: s.techno_open.stats.acknowledged,
        waiting,
    }
}

/// The runtime's cycle statistics in one update.
#[derive(Debug, Clone, Serialize)]
pub struct CycleView {
    pub period_us: f64,
    pub ticks: u64,
    pub work_last_us: f64,
    pub work_mean_us: f64,
    pub work_max_us: f64,
    pub late_last_us: f64,
    pub late_max_us: f64,
    pub overruns: u64,
}

/// The cycle statistics over the last seconds (`feed::CYCLE_WINDOW_S`), from the runtime's
/// live work histogram: quantiles are bucket edges, at most 19 % above the true value.
#[derive(Debug, Clone, Serialize)]
pub struct WindowView {
    /// Seconds the window covers so far.
    pub seconds: usize,
    pub ticks: u64,
    pub work_p50_us: f64,
    pub work_p99_us: f64,
    pub work_p999_us: f64,
    /// Ticks whose lateness and work together exceeded the period, in the window.
    pub overruns: u64,
    /// The p99 of each past second, µs, oldest first (at most a minute).
    pub p99_trend_us: Vec<f64>,
}

impl WindowView {
    pub fn new(counts: &[u64], seconds: usize, ticks: u64, overruns: u64, trend: Vec<f64>) -> Self {
        use crate::vocab::stats::work_quantile_us;
        WindowView {
            seconds,
            ticks,
            work_p50_us: work_quantile_us(counts, 0.5),
            work_p99_us: work_quantile_us(counts, 0.99),
            work_p999_us: work_quantile_us(counts, 0.999),
            overruns,
            p99_trend_us: trend,
        }
    }
}

/// One update: the `status` event of the stream, and `GET /snapshot.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Update {
    /// Counts the feed's updates, so a page can tell how many it missed.
    pub seq: u64,
    /// Since the runtime started.
    pub cycle: Option<CycleView>,
    /// Over the last seconds (`None` without the runtime's live statistics).
    pub window: Option<WindowView>,
    pub channels: Vec<ChannelView>,
    /// `serve --soak --http`: the soak's counters per channel and its invariants so far
    /// (as the soak's report has them), published twice a second.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub soak: Option<serde_json::Value>,
}

/// A channel's program text for the listing: the `listing` event.
#[derive(Debug, Clone, Serialize)]
pub struct ListingView {
    pub ch: u16,
    pub program: Option<String>,
    pub lines: Vec<String>,
    /// Lines left out after `lines` (the listing is capped at [`MAX_LISTING_LINES`]).
    pub lines_left_out: usize,
}

/// Lines of a program the listing shows at most; a bigger program is cut (the page would
/// not show more usefully, and one event stays bounded).
pub const MAX_LISTING_LINES: usize = 20_000;

/// A program's text split into lines once, with where each starts, so the executing block's
/// byte offset finds its line by a binary search on every update.
#[derive(Debug, Clone)]
pub struct Listing {
    pub program: Arc<str>,
    line_starts: Vec<usize>,
    text: Arc<Vec<u8>>,
}

impl Listing {
    pub fn new(program: Arc<str>, text: Arc<Vec<u8>>) -> Self {
        let line_starts = std::iter::once(0)
            .chain(memchr::memchr_iter(b'\n', &text).map(|i| i + 1))
            .filter(|&s| s < text.len())
            .collect();
        Listing {
            program,
            line_starts,
            text,
        }
    }

    /// Byte offset where 1-based `line` starts.
    pub fn line_start(&self, line: usize) -> Option<u64> {
        let i = line.checked_sub(1)?;
        self.line_starts.get(i).map(|&s| s as u64)
    }

    /// 1-based line holding byte `offset`.
    pub fn line_of(&self, offset: u64) -> usize {
        let offset = usize::try_from(offset).unwrap_or(usize::MAX);
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    pub fn view(&self, ch: u16) -> ListingView {
        let lines: Vec<String> = self
            .line_starts
            .iter()
            .take(MAX_LISTING_LINES)
            .enumerate()
            .map(|(i, &start)| {
                let end = self
                    .line_starts
                    .get(i + 1)
                    .copied()
                    .unwrap_or(self.text.len());
                let raw = self.text.get(start..end).unwrap_or_default();
                String::from_utf8_lossy(raw)
                    .trim_end_matches(['\r', '\n'])
                    .to_string()
            })
            .collect();
        ListingView {
            ch,
            program: Some(self.program.to_string()),
            lines_left_out: self.line_starts.len() - lines.len(),
            lines,
        }
    }
}

fn us(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

/// The cycle statistics: work times through the door (every status carries the machine's),
/// lateness and overruns from the runtime's live counters.
pub fn cycle_view(s: &Status, live: Option<LiveCycleReading>) -> CycleView {
    let live = live.unwrap_or_default();
    CycleView {
        period_us: us(s.period),
        ticks: s.cycle_times.ticks,
        work_last_us: us(s.cycle_times.last),
        work_mean_us: us(s.cycle_times.mean()),
        work_max_us: us(s.cycle_times.max),
        late_last_us: us(live.late_last),
        late_max_us: us(live.late_max),
        overruns: live.overruns,
    }
}

/// Share of the listing's bytes before `offset` (0..=1).
impl Listing {
    pub fn share_before(&self, offset: u64) -> f64 {
        let len = self.text.len().max(1) as f64;
        (offset as f64 / len).clamp(0.0, 1.0)
    }
}

/// One channel's view; `listing` is the text the page shows for it, if any.
pub fn channel_view(
    ch: u16,
    s: &Status,
    listing: Option<&Listing>,
    recorded: Recorded,
) -> ChannelView {
    let block = s.active_block.as_ref();
    let line = match (block, listing) {
        (Some(b), Some(l)) if *b.prog == *l.program => Some(l.line_of(b.offset)),
        _ => None,
    };
    let axes = s
        .positions
        .iter()
        .zip(&s.pcs_positions)
        .map(|(&(axis, mcs_mm), &(_, pcs_mm))| AxisView {
            axis,
            mcs_mm,
            pcs_mm,
        })
        .collect();
    ChannelView {
        ch,
        mode: s.mode,
        state: s.state,
        axes,
        distance_to_go_mm: s.distance_to_go_mm,
        feed_mm_per_min: s.modal.feed_mm_per_min,
        velocity_mm_per_s: s.velocity_mm_per_s,
        override_pct: s.override_pct,
        program: s.program.clone(),
        block_program: block.map(|b| b.prog.to_string()),
        line,
        block_counter: s.block_counter,
        block_n: block.and_then(|b| b.n),
        stream_used_bytes: s.stream_used,
        stream_free_bytes: s.stream_free,
        blocks: s.blocks,
        errors_total: s.errors_total,
        last_error: s.last_error.as_ref().map(|(code, text)| {
            let (program, line) = s.last_error_at.clone().unwrap_or_default();
            ErrorView {
                index: s.errors_total.saturating_sub(1),
                code: *code,
                text: text.clone(),
                program,
                line,
            }
        }),
        message: s.message.clone(),
        techno: techno_view(s),
        executing_feed_mm_per_min: s.executing_feed_mm_per_min,
        executing_rapid: s.executing_rapid,
        spindle: SpindleView {
            direction: recorded.executed.spindle.unwrap_or(s.modal.spindle).name(),
            rpm: recorded.executed.spindle_rpm.unwrap_or(s.modal.spindle_rpm),
        },
        tool: recorded.executed.tool.unwrap_or(s.modal.tool),
        tool_offset: s.modal.tool_offset,
        g_codes: s.modal.g_codes().to_vec(),
        work_offset_mm: {
            let o = s
                .modal
                .zero_offset
                .checked_sub(1)
                .and_then(|i| s.zero_offsets.get(i))
                .copied()
                .unwrap_or_default();
            [o[0], o[1], o[2]]
        },
        elapsed_s: recorded.elapsed_s,
        remaining_s: recorded.remaining_s,
        stream_refused_full: s.stream_writes_full,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_find_their_lines() {
        let l = Listing::new(
            Arc::from("p.nc"),
            Arc::new(b"N10 G01 X1\r\nN20 X2\nN30 M30\n".to_vec()),
        );
        assert_eq!(l.line_of(0), 1);
        assert_eq!(l.line_of(12), 2);
        assert_eq!(l.line_of(19), 3);
        let v = l.view(1);
        assert_eq!(v.lines, ["N10 G01 X1", "N20 X2", "N30 M30"]);
        assert_eq!(v.lines_left_out, 0);
    }

    #[test]
    fn functions_read_as_programmed() {
        assert_eq!(function_text(TechnoKind::M, 25, 0), "M25");
        assert_eq!(function_text(TechnoKind::M, 200, 1200), "M200=1200");
        assert_eq!(function_text(TechnoKind::H, 7, 2), "H7=2");
        assert_eq!(function_text(TechnoKind::S, 12000, 12000), "S12000");
        assert_eq!(function_text(TechnoKind::T, 2, 0), "T2");
    }
}
