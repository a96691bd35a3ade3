//! The event log and the report as files users parse: one JSON object a line with the field
//! names of the README, nothing lost at shutdown, identical logs from identical virtual runs.

use std::collections::BTreeMap;
use std::time::Duration;

use ncchannel::report::event::{Event, EventKind, EventLog, ProgramEndKind};
use ncchannel::report::summary::{
    CycleReport, ErrorReport, FilesReport, Outcome, Report, StreamReport,
};
use ncchannel::runtime::{Clock, RunEnd, Runtime, Tick};
use ncchannel::vocab::event::CacheOp;
use ncchannel::vocab::flush::FlushKind;
use ncchannel::vocab::mode::{Mode, State};
use ncchannel::vocab::stats::CycleStats;
use serde_json::Value;

use crate::support::streaming_load;
use streaming_load::{generated_program, StreamingLoad};

fn keys(line: &str) -> Vec<String> {
    // Field names as a sorted set; the order of the leading four is checked on the text.
    let v: Value = serde_json::from_str(line).unwrap();
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

fn sorted(names: &[&str]) -> Vec<String> {
    let mut k: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    k.sort();
    k
}

/// One documented event kind: the kind, its `ev` name and its own field names.
type Case = (EventKind, &'static str, Vec<&'static str>);

#[test]
fn every_event_kind_has_the_documented_fields() {
    let tick = Tick {
        index: 1500,
        period: Duration::from_millis(1),
        time: Duration::from_millis(1500),
        clock: ncchannel::runtime::Clock::Virtual,
    };
    let mut cases = program_event_cases();
    cases.extend(message_event_cases());
    for (kind, ev, fields) in cases {
        let line = Event::new(&tick, 2, kind).to_json();
        assert!(!line.contains('\n'));
        assert!(
            line.starts_with(&format!(r#"{{"tick":1500,"t":1.5,"ch":2,"ev":"{ev}""#)),
            "{line}"
        );
        let mut want = vec!["tick", "t", "ch", "ev"];
        want.extend(fields);
        assert_eq!(keys(&line), sorted(&want), "{line}");
    }
}

/// An owned string, to keep the case table short.
fn s(x: &str) -> String {
    x.to_string()
}

/// State, program and stream events.
fn program_event_cases() -> Vec<Case> {
    vec![
        (
            EventKind::State {
                mode: Mode::Automatic,
                state: State::Active,
            },
            "state",
            vec!["mode", "state"],
        ),
        (
            EventKind::ProgramStart {
                prog: s("streaming.nc"),
                stream: true,
            },
            "program_start",
            vec!["prog", "stream"],
        ),
        (
            EventKind::ProgramEnd {
                prog: s("streaming.nc"),
                end: ProgramEndKind::M30,
            },
            "program_end",
            vec!["prog", "end"],
        ),
        (
            EventKind::Block {
                prog: s("streaming.nc"),
                line: 3,
                offset: 40,
                counter: 3,
                n: Some(30),
                text: s("N30 X10"),
            },
            "block",
            vec!["prog", "line", "offset", "counter", "n", "text"],
        ),
        (
            EventKind::Write {
                bytes: 992,
                ok: true,
                code: None,
            },
            "write",
            vec!["bytes", "ok", "code"],
        ),
        (EventKind::Segment { bytes: 10 }, "segment", vec!["bytes"]),
        (EventKind::Discard { bytes: 10 }, "discard", vec!["bytes"]),
    ]
}

/// Messages, interruptions, cache, flush and search events.
fn message_event_cases() -> Vec<Case> {
    vec![
        (
            EventKind::Warning {
                code: 11012,
                msg: s("Error writing the object"),
            },
            "warning",
            vec!["code", "msg"],
        ),
        (
            EventKind::Error {
                code: 21476,
                msg: s("no line end"),
                prog: Some(s("streaming.nc")),
                line: Some(7),
            },
            "error",
            vec!["code", "msg", "prog", "line"],
        ),
        (EventKind::Interrupt { held: 2 }, "interrupt", vec!["held"]),
        (EventKind::Resume, "resume", vec![]),
        (
            EventKind::Cache {
                op: CacheOp::Load,
                file: Some(s("sub.nc")),
            },
            "cache",
            vec!["op", "file"],
        ),
        (
            EventKind::Flush {
                kind: FlushKind::Continue,
            },
            "flush",
            vec!["kind"],
        ),
        (
            EventKind::Search {
                target: s("n:30"),
                found: true,
            },
            "search",
            vec!["target", "found"],
        ),
    ]
}

/// Run the synthetic streaming load in virtual time with the events going to `path`.
fn logged_run(path: &std::path::Path) -> (u64, u64) {
    let log = EventLog::to_file(path).unwrap();
    // Reading every 5th tick while writing full packets each tick fills the buffer: 11012s.
    let load = StreamingLoad::new(generated_program(600), 992, 5, false, log).unwrap();
    let (mut rt, _tx) = Runtime::new(load, Duration::from_millis(1), Clock::Virtual);
    let s = rt.run(Some(100_000));
    assert_eq!(s.end, RunEnd::Stopped);
    let (load, _) = rt.into_inner();
    let c = *load.stream().counters();
    let expected_events = c.writes_ok + c.writes_full + c.segments;
    let lines = load.finish().unwrap();
    assert_eq!(lines, expected_events);
    (lines, c.writes_full)
}

#[test]
fn identical_virtual_runs_give_identical_event_logs_and_lose_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.jsonl"), dir.path().join("b.jsonl"));
    let (lines, rejected) = logged_run(&a);
    logged_run(&b);
    let ta = std::fs::read_to_string(&a).unwrap();
    let tb = std::fs::read_to_string(&b).unwrap();
    assert_eq!(ta, tb);
    assert!(rejected > 0, "the run should have provoked 11012");
    assert_eq!(ta.lines().count() as u64, lines);
    let mut last_tick = 0;
    let mut seen_reject = false;
    for line in ta.lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        let tick = v["tick"].as_u64().unwrap();
        assert!(tick >= last_tick, "events in tick order");
        last_tick = tick;
        assert_eq!(v["t"].as_f64().unwrap(), tick as f64 / 1000.0);
        assert_eq!(v["ch"], 1);
        if v["ev"] == "write" && v["ok"] == false {
            assert_eq!(v["code"], 11012);
            seen_reject = true;
        }
    }
    assert!(seen_reject);
}

#[test]
fn a_disabled_log_takes_events_and_writes_nothing() {
    let mut log = EventLog::disabled();
    assert!(!log.enabled());
    let mut buf = log.buffer();
    assert!(!buf.enabled());
    let tick = Tick::first(Duration::from_millis(1), ncchannel::runtime::Clock::Virtual);
    buf.push(&tick, 1, EventKind::Interrupt { held: 0 });
    assert!(buf.is_empty());
    buf.flush_to(&mut log);
    assert_eq!(log.finish().unwrap(), 0);
}

/// A report with one of each part: two errors (one raised by a program line), files, cycle.
fn sample_report() -> Report {
    let mut stats = CycleStats::default();
    for us in [100u64, 120, 130, 900] {
        stats.work.record_ns(us * 1000 / 100);
        stats.lateness.record_ns(us * 10);
    }
    Report {
        outcome: Outcome::MaxTicks,
        ticks: 4,
        time_s: 0.004,
        wall_s: 0.0001,
        blocks: 2,
        position: BTreeMap::from([("X".to_string(), 10.0), ("Y".to_string(), -2.5)]),
        stream: StreamReport {
            writes_ok: 3,
            writes_rejected: 1,
            bytes: 120,
        },
        interrupts: 1,
        errors: vec![
            ErrorReport {
                code: 21476,
                msg: "Streaming data does not contain a correct line end marker".into(),
                prog: None,
                line: None,
            },
            ErrorReport {
                code: 21897,
                msg: "Axis position is out of permissible value range".into(),
                prog: Some("part.nc".into()),
                line: Some(12),
            },
        ],
        cycle: CycleReport::new(Duration::from_millis(1), &stats),
        files: FilesReport {
            opens: 3,
            bytes_read: 700,
            cache_hits: 5,
            latency_s: 0.0006,
        },
        techno: Default::default(),
    }
}

#[test]
fn report_json_has_the_documented_shape() {
    let r = sample_report();
    let v: Value = serde_json::from_str(&r.to_json_pretty()).unwrap();
    assert_eq!(v["outcome"], "max_ticks");
    assert_eq!(
        keys(&v.to_string()),
        sorted(&[
            "outcome",
            "ticks",
            "time_s",
            "wall_s",
            "blocks",
            "position",
            "stream",
            "interrupts",
            "errors",
            "cycle",
            "files",
            "techno"
        ])
    );
    assert_eq!(
        keys(&v["files"].to_string()),
        sorted(&["opens", "bytes_read", "cache_hits", "latency_s"])
    );
    assert_eq!(
        keys(&v["techno"].to_string()),
        sorted(&["output", "acknowledged", "waited_s", "dropped_by_reset"])
    );
    assert_eq!(v["position"]["Y"], -2.5);
    assert_eq!(
        keys(&v["stream"].to_string()),
        sorted(&["writes_ok", "writes_rejected", "bytes"])
    );
    assert_eq!(v["errors"][0]["code"], 21476);
    // Where no program line raised the error, the report says nothing of one.
    assert_eq!(keys(&v["errors"][0].to_string()), sorted(&["code", "msg"]));
    assert_eq!(v["errors"][1]["prog"], "part.nc");
    assert_eq!(v["errors"][1]["line"], 12);
    assert_eq!(
        keys(&v["cycle"].to_string()),
        sorted(&[
            "period_us",
            "work_us_p50",
            "work_us_p99",
            "work_us_max",
            "late_us_p99",
            "overruns",
            "clock_stopped_s"
        ])
    );
    assert_eq!(v["cycle"]["period_us"], 1000.0);
    assert_eq!(v["cycle"]["work_us_max"], 9.0);
    let back: Report = serde_json::from_value(v).unwrap();
    assert_eq!(back, r);
}

#[test]
fn report_summary_names_errors_with_their_program_line() {
    let r = sample_report();
    let mut human = Vec::new();
    r.print_human(&mut human).unwrap();
    let human = String::from_utf8(human).unwrap();
    for want in [
        "stopped at --max-ticks",
        "blocks:     2",
        "0.004 s channel time",
        "interrupts: 1",
        "3 writes accepted, 1 rejected",
        "error 21476: Streaming data does not contain a correct line end marker\n",
        "error 21897: Axis position is out of permissible value range (part.nc, line 12)\n",
        "3 opens, 700 bytes read, 5 cache hits",
    ] {
        assert!(human.contains(want), "{want:?} missing in\n{human}");
    }
}

/// The typed fields spell what the log has always said: ISG's mode and state names, the M
/// function of a program end, `plain` for `#FLUSH`, snake_case cache operations.
#[test]
fn typed_fields_serialise_to_the_documented_words() {
    let tick = Tick {
        index: 1,
        period: Duration::from_millis(1),
        time: Duration::from_millis(1),
        clock: ncchannel::runtime::Clock::Virtual,
    };
    let json = |kind: EventKind| -> Value {
        serde_json::from_str(&Event::new(&tick, 1, kind).to_json()).unwrap()
    };
    let v = json(EventKind::State {
        mode: Mode::Manual,
        state: State::Hold,
    });
    assert_eq!(
        (v["mode"].as_str(), v["state"].as_str()),
        (Some("MANUAL"), Some("HOLD"))
    );
    for (end, word) in [
        (ProgramEndKind::M30, "M30"),
        (ProgramEndKind::M2, "M2"),
        (ProgramEndKind::Reset, "reset"),
    ] {
        let v = json(EventKind::ProgramEnd {
            prog: "p.nc".into(),
            end,
        });
        assert_eq!(v["end"], word);
    }
    for (kind, word) in [
        (FlushKind::Stop, "plain"),
        (FlushKind::Continue, "continue"),
        (FlushKind::Wait, "wait"),
    ] {
        assert_eq!(json(EventKind::Flush { kind })["kind"], word);
    }
    for (op, word) in [
        (CacheOp::Load, "load"),
        (CacheOp::Refresh, "refresh"),
        (CacheOp::Clear, "clear"),
        (CacheOp::ClearAll, "clear_all"),
        (CacheOp::Hit, "hit"),
    ] {
        assert_eq!(json(EventKind::Cache { op, file: None })["op"], word);
    }
}
