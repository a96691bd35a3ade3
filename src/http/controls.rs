//! The page's operator controls: `POST /control/<channel>/<action>` becomes one door
//! [`Op`], the same a PLC's ADS write makes, and the channel's answer becomes the HTTP status.
//!
//! Refused with 403 unless `serve --http-controls` allowed them. A control request must carry
//! the [`CONTROL_HEADER`] the page sends: a browser lets another web site POST to this address
//! only without custom headers (a "simple" cross-origin request; Fetch standard, "CORS
//! protocol"), so that site cannot command the channels through a user's browser.

use super::snapshot::Listing;
use super::{Backend, ControlAccess};
use crate::machine::remote::DeviceError;
use crate::machine::SearchTarget;
use crate::machine::{Op, Reply};
use crate::vocab::mode::State;

/// The header every control request carries (any value).
pub const CONTROL_HEADER: &str = "X-Ncchannel-Control";

/// What an operator asks of a channel.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Start the selected program (or resume), as the ACTIVE command does.
    Start,
    /// Start this program (the command parameter and ACTIVE in one step).
    StartProgram(String),
    Hold,
    Resume,
    Reset,
    /// Feed override, percent.
    Override(f64),
    /// Start `program` from a block on: a line of its listing or an N number, by the
    /// channel's block search (as `run --search` does).
    RunFrom {
        program: String,
        from: StartAt,
    },
    /// One NC block, executed through the stream interface: the streaming program started,
    /// the block and an `M30` written into the stream, as a streaming client does.
    Mdi(String),
    /// An incremental move of one axis by this distance, mm, at [`JOG_FEED_MM_PER_MIN`]
    /// (an MDI block `G91 G01 X… F…`).
    Jog {
        axis: char,
        distance_mm: f64,
    },
}

/// Feed of a jog, mm/min.
pub const JOG_FEED_MM_PER_MIN: f64 = 1000.0;
/// Longest MDI block, bytes.
pub const MAX_MDI_BYTES: usize = 256;
/// Largest jog step, mm.
pub const MAX_JOG_MM: f64 = 100.0;

/// Where a run from a line starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartAt {
    /// 1-based line of the program's listing.
    Line(usize),
    /// The first block with this N number.
    BlockNumber(u32),
}

/// The HTTP answer to a control request: status code and a line of text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Answer {
    pub status: u16,
    pub text: String,
}

impl Answer {
    fn new(status: u16, text: impl Into<String>) -> Self {
        Answer {
            status,
            text: text.into(),
        }
    }
}

/// `<action>` and the request body (the program name, the override percent).
pub fn parse_action(name: &str, body: &str) -> Result<Action, String> {
    let body = body.trim();
    Ok(match name {
        "start" if body.is_empty() => Action::Start,
        "start" => Action::StartProgram(body.to_string()),
        "hold" => Action::Hold,
        "resume" => Action::Resume,
        "reset" => Action::Reset,
        "run-from-line" => {
            let (program, at) = body.split_once('\n').ok_or(
                "run-from-line: the body is the program, a line feed, and a line or N number",
            )?;
            let at = at.trim();
            let from = match at.strip_prefix(['N', 'n']) {
                Some(n) => n.parse().map(StartAt::BlockNumber),
                None => at.parse().map(StartAt::Line),
            }
            .ok()
            .filter(|f| *f != StartAt::Line(0))
            .ok_or_else(|| {
                format!("run-from-line: '{at}' is neither a line (1, 2 …) nor an N number")
            })?;
            Action::RunFrom {
                program: program.trim().to_string(),
                from,
            }
        }
        "mdi" => {
            let ok = !body.is_empty()
                && body.len() <= MAX_MDI_BYTES
                && body.bytes().all(|b| (b' '..=b'~').contains(&b));
            if !ok {
                return Err(format!(
                    "mdi: one NC block of printable characters, at most {MAX_MDI_BYTES} bytes"
                ));
            }
            Action::Mdi(body.to_string())
        }
        "jog" => {
            let mut chars = body.chars();
            let axis = chars.next().map(|c| c.to_ascii_uppercase());
            let distance_mm = chars.as_str().trim().parse::<f64>().ok();
            match (axis, distance_mm) {
                (Some(axis @ ('X' | 'Y' | 'Z')), Some(d))
                    if d.is_finite() && d != 0.0 && d.abs() <= MAX_JOG_MM =>
                {
                    Action::Jog {
                        axis,
                        distance_mm: d,
                    }
                }
                _ => {
                    return Err(format!(
                        "jog: an axis X, Y or Z and a distance of at most {MAX_JOG_MM} mm ('X-1')"
                    ))
                }
            }
        }
        "override" => match body.parse::<f64>() {
            Ok(p) if p.is_finite() => Action::Override(p),
            _ => return Err(format!("override: '{body}' is not a percentage")),
        },
        other => return Err(format!("unknown control '{other}'")),
    })
}

fn op(action: Action) -> Op {
    match action {
        // Applied in steps by `run_from` (the search target, then the start).
        Action::RunFrom { program, .. } => Op::Start(program),
        // Applied in steps by `mdi`; never reaches here.
        Action::Mdi(_) | Action::Jog { .. } => Op::Status,
        Action::Start => Op::CommandState(State::Active as i32),
        Action::StartProgram(p) => Op::Start(p),
        Action::Hold => Op::Hold,
        Action::Resume => Op::Resume,
        Action::Reset => Op::Reset,
        Action::Override(p) => Op::SetOverride(p),
    }
}

/// Apply one control request: `path_rest` is `<channel>/<action>`.
pub fn handle(
    backend: &Backend,
    access: ControlAccess,
    has_header: bool,
    path_rest: &str,
    body: &str,
) -> Answer {
    if access == ControlAccess::Refused {
        return Answer::new(
            403,
            "operator controls are off: start serve with --http-controls to allow them",
        );
    }
    if !has_header {
        return Answer::new(
            403,
            format!("control requests must carry the {CONTROL_HEADER} header (the page sends it)"),
        );
    }
    let Some((ch, name)) = path_rest.split_once('/') else {
        return Answer::new(404, "use /control/<channel>/<action>");
    };
    let Ok(ch) = ch.parse::<u16>() else {
        return Answer::new(404, format!("no channel '{ch}'"));
    };
    let action = match parse_action(name, body) {
        Ok(a) => a,
        Err(msg) => return Answer::new(400, msg),
    };
    let block = match &action {
        Action::Mdi(b) => Some(b.clone()),
        Action::Jog { axis, distance_mm } => Some(format!(
            "G91 G01 {axis}{distance_mm:.4} F{JOG_FEED_MM_PER_MIN:.0}"
        )),
        _ => None,
    };
    if let Some(block) = block {
        return mdi(backend, ch, &block);
    }
    if let Action::RunFrom { program, from } = &action {
        if let Err(a) = search_target(backend, ch, program, *from) {
            return a;
        }
    }
    match backend.call(ch, op(action)) {
        Ok(Reply::Done | Reply::Command(Ok(()))) => Answer::new(200, "done"),
        Ok(Reply::Command(Err(e))) => Answer::new(409, e.to_string()),
        Ok(_) => Answer::new(500, "unexpected answer from the channel"),
        Err(DeviceError::NotFound) => Answer::new(404, format!("no channel {ch}")),
        Err(e) => Answer::new(503, format!("not applied: {e}")),
    }
}

/// Execute one block through the channel's stream interface, with the requests a streaming
/// client makes over ADS: start the streaming program, write the block and an `M30` (the
/// program ends after it, so the channel is READY again and G91 is gone with it). Refused
/// with the channel's own reason: busy, no streaming program, the write refused.
fn mdi(backend: &Backend, ch: u16, block: &str) -> Answer {
    let status = match backend.status(ch) {
        Ok(s) => s,
        Err(DeviceError::NotFound) => return Answer::new(404, format!("no channel {ch}")),
        Err(e) => return Answer::new(503, format!("not applied: {e}")),
    };
    let Some(stream) = status.streaming_program.clone() else {
        return Answer::new(
            409,
            "the channel has no streaming program (streaming_prog_file): MDI goes through the stream",
        );
    };
    match backend.call(ch, Op::Start(stream)) {
        Ok(Reply::Command(Ok(()))) => {}
        Ok(Reply::Command(Err(e))) => return Answer::new(409, e.to_string()),
        Ok(_) => return Answer::new(500, "unexpected answer from the channel"),
        Err(e) => return Answer::new(503, format!("not applied: {e}")),
    }
    let packet: std::sync::Arc<[u8]> = format!("{block}\r\nM30\r\n").into_bytes().into();
    match backend.call(ch, Op::WriteStream(packet)) {
        Ok(Reply::Stream(Ok(()))) => Answer::new(200, "done"),
        Ok(Reply::Stream(Err(e))) => Answer::new(409, e.to_string()),
        Ok(Reply::StreamNotReady) => Answer::new(409, "the stream takes no data now (ERROR)"),
        Ok(_) => Answer::new(500, "unexpected answer from the channel"),
        Err(e) => Answer::new(503, format!("not applied: {e}")),
    }
}

/// Set the channel's block search target for a run from `from` (`Op::SearchAt`, the door
/// `run --search` uses): a line becomes the byte offset of its start in the program's text,
/// which the channel knows once the program has run (its listing).
fn search_target(backend: &Backend, ch: u16, program: &str, from: StartAt) -> Result<(), Answer> {
    let target = match from {
        StartAt::BlockNumber(n) => SearchTarget::BlockNumber(n),
        StartAt::Line(line) => {
            let text = match backend.call(ch, Op::ProgramText(std::sync::Arc::from(program))) {
                Ok(Reply::ProgramText(Some(t))) => t,
                _ => {
                    return Err(Answer::new(
                        409,
                        format!("the channel has no text of {program} yet (it has not run): run from its N number instead"),
                    ))
                }
            };
            let listing = Listing::new(std::sync::Arc::from(program), text);
            let Some(offset) = listing.line_start(line) else {
                return Err(Answer::new(409, format!("{program} has no line {line}")));
            };
            SearchTarget::Offset(offset)
        }
    };
    match backend.call(ch, Op::SearchAt(Some(target))) {
        Ok(Reply::Done) => Ok(()),
        Ok(_) => Err(Answer::new(500, "unexpected answer from the channel")),
        Err(DeviceError::NotFound) => Err(Answer::new(404, format!("no channel {ch}"))),
        Err(e) => Err(Answer::new(503, format!("not applied: {e}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn actions_parse_with_their_values() {
        assert_eq!(parse_action("start", ""), Ok(Action::Start));
        assert_eq!(
            parse_action("start", "demo.nc\n"),
            Ok(Action::StartProgram("demo.nc".into()))
        );
        assert_eq!(parse_action("override", "50"), Ok(Action::Override(50.0)));
        assert!(parse_action("override", "NaN").is_err());
        assert!(parse_action("launch", "").is_err());
        assert_eq!(
            parse_action("run-from-line", "square.nc\n5"),
            Ok(Action::RunFrom {
                program: "square.nc".into(),
                from: StartAt::Line(5)
            })
        );
        assert_eq!(
            parse_action("run-from-line", "square.nc\nN40"),
            Ok(Action::RunFrom {
                program: "square.nc".into(),
                from: StartAt::BlockNumber(40)
            })
        );
        assert!(parse_action("run-from-line", "square.nc\n0").is_err());
        assert!(parse_action("run-from-line", "square.nc").is_err());
        assert_eq!(
            parse_action("jog", "x-1.5"),
            Ok(Action::Jog {
                axis: 'X',
                distance_mm: -1.5
            })
        );
        assert!(parse_action("jog", "A1").is_err());
        assert!(parse_action("jog", "X1000").is_err());
        assert!(parse_action("mdi", "G01 X1\r\nM30").is_err());
        assert_eq!(
            parse_action("mdi", "G01 X10 F1000"),
            Ok(Action::Mdi("G01 X10 F1000".into()))
        );
    }
}
