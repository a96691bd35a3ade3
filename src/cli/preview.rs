//! The whole-program preview of the live view: a file program run on a private copy of the
//! channels, from the same lists, in virtual time, its path recorded as the live view records
//! a running channel's (`machine::live`), so the page draws what the program will do before
//! and while it runs. The geometry is the interpolator's own (arcs, contour blending,
//! splines), not a second reading of the program.

use std::sync::Arc;
use std::time::Duration;

use crate::http::path::PathStore;
use crate::http::preview::{Preview, Previewer, PREVIEW_MAX_S};
use crate::machine::{Machine, Op, Reply, StopWhen};
use crate::params::Config;
use crate::report::event::EventLog;
use crate::runtime::{RunEnd, Runtime};
use crate::source::loader::Loader;
use crate::vocab::tick::{Clock, Tick};

/// Ticks between two drains of the private record (well within its pending points).
const CHUNK_TICKS: u64 = 1000;

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
