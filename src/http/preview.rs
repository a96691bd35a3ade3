//! The whole-program preview: a file program run on a private copy of the channels, from the
//! same lists, in virtual time, its path recorded as the live view records a running
//! channel's (`machine::live`), so the page draws what the program will do before and while
//! it runs. The geometry is the interpolator's own (arcs, contour blending, splines), not a
//! second reading of the program.

use std::sync::Arc;
use std::time::Duration;

use serde::Serialize;

use super::path::{PathStore, PathUpdate};
use crate::machine::{Machine, Op, Reply, StopWhen};
use crate::params::Config;
use crate::report::event::EventLog;
use crate::runtime::{RunEnd, Runtime};
use crate::source::loader::Loader;
use crate::vocab::tick::{Clock, Tick};

/// Channel time a preview runs at most, s: a longer program's preview is cut there (and says
/// so).
pub const PREVIEW_MAX_S: f64 = 600.0;
/// Ticks between two drains of the private record (well within its pending points).
const CHUNK_TICKS: u64 = 1000;

/// A preview of one program on one channel.
#[derive(Debug, Serialize)]
pub struct Preview {
    pub program: String,
    #[serde(flatten)]
    pub path: PathUpdate,
    /// The program ran to its end (else it was cut at [`PREVIEW_MAX_S`] or stopped by an
    /// error, given in `error`).
    pub complete: bool,
    /// Channel time the program took, s (to the cut).
    pub seconds: f64,
    pub error: Option<String>,
}

/// What computes a preview: channel number and program name to the preview, or the reason.
pub type Previewer = Arc<dyn Fn(u16, &str) -> Result<Preview, String> + Send + Sync>;

/// Previews from the channels of `config`.
pub fn previewer(config: Config, loader: Loader) -> Previewer {
    Arc::new(move |ch, program| preview(&config, &loader, ch, program))
}

fn preview(config: &Config, loader: &Loader, ch: u16, program: &str) -> Result<Preview, String> {
    let channels = crate::setup::channels(config, false, loader).map_err(|e| e.to_string())?;
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::ProgramsFinished);
    machine.record_live();
    let period = Duration::from_micros(config.runtime.cycle_period_us.max(1));
    let tick0 = Tick::first(period, Clock::Virtual);
    match machine.apply(&tick0, u32::from(ch), Op::Start(program.to_string())) {
        Reply::Command(Err(e)) => return Err(e.to_string()),
        Reply::NoChannel => return Err(format!("no channel {ch}")),
        _ => {}
    }
    let (mut rt, _requests) = Runtime::new(machine, period, Clock::Virtual);
    let max_ticks = (PREVIEW_MAX_S / period.as_secs_f64()) as u64;
    let mut store = PathStore::default();
    let complete = loop {
        let s = rt.run(Some(CHUNK_TICKS));
        if let Reply::Live(mut d) = rt.cycle_mut().apply(&tick0, u32::from(ch), Op::DrainLive) {
            store.extend(ch, &mut d);
        }
        if s.end != RunEnd::MaxTicks {
            break true;
        }
        if rt.ticks() >= max_ticks {
            break false;
        }
    };
    let status = match rt.cycle_mut().apply(&tick0, u32::from(ch), Op::Status) {
        Reply::Status(s) => Some(s),
        _ => None,
    };
    let error = status
        .and_then(|s| s.last_error)
        .map(|(code, text)| format!("{code}: {text}"));
    Ok(Preview {
        program: program.to_string(),
        path: store.whole(ch),
        complete: complete && error.is_none(),
        seconds: rt.time().as_secs_f64(),
        error,
    })
}
