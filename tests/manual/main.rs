//! The manual corpus: the example programs of the TF5200 programming manual's pages, one `.nc`
//! file each in this folder, run in a channel and checked against what the page says they do.
//!
//! A file's header cites its page (`; TF5200 programming manual, "<page title>"`) and states
//! the documented outcome in `; expect:` lines:
//!
//! - `end X=10 Y=0` — where the named axes stand when the program has ended, mm;
//! - `msg "text"` — one operator message (`#MSG`), the `msg` lines in the order they come;
//! - `error 20xxx` — the run stops with this error id;
//! - `warning 20xxx` — the run reports this warning id (and goes on);
//! - `blocks N10 N20 N40` — the numbered blocks that run, in order (unnumbered ones not
//!   listed);
//! - `runs N110 46` — the block numbered N110 runs 46 times;
//! - `dwell N40 2.0 s` — the block numbered N40 lasts 2.0 s (to the next block's start).
//!
//! Without an `error` line the program must end without one. A line `; run: stream` runs the
//! main program through the data-streaming interface (CR LF lines) instead of as a file, for
//! the examples of the TF5200 data streaming manual. A line `; --- file <name>`
//! starts a further program file (a subroutine or cycle the example calls); the lines before
//! the first such line are the main program.
//!
//! Examples ncchannel cannot run yet are listed in `REFUSED.md` with the reason; the test fails
//! when an unlisted example does not behave as documented, and when a listed one now does (so
//! the list stays true). It prints how many behave.

#[path = "../support/mod.rs"]
mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ncchannel::channel::Finish;
use support::{feeder, Rig, RunResult};

/// Most ticks one example may run (1 ms each: 1000 s of channel time).
const MAX_TICKS: u64 = 1_000_000;
/// How close a position must be, mm, and a dwell, s.
const POSITION_TOL_MM: f64 = 1e-3;
const DWELL_TOL_S: f64 = 0.01;

/// runtime.toml's axes for the corpus: X Y Z with the default limits, and U.
const AXES_TOML: &str =
    "[[axes]]\nname = \"X\"\n[[axes]]\nname = \"Y\"\n[[axes]]\nname = \"Z\"\n[[axes]]\nname = \"U\"\n";

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/manual")
}

/// One example's documented outcome.
#[derive(Debug, Default)]
struct Expect {
    end: Vec<(char, f64)>,
    msgs: Vec<String>,
    error: Option<u64>,
    warnings: Vec<u64>,
    blocks: Option<Vec<u64>>,
    runs: Vec<(u64, usize)>,
    dwells: Vec<(u64, f64)>,
}

/// One example: its main program, its further files, what it should do.
struct Example {
    main: String,
    /// Fed through the streaming interface rather than started as a file.
    stream: bool,
    files: Vec<(String, String)>,
    expect: Expect,
}

fn parse_example(name: &str, text: &str) -> Result<Example, String> {
    let mut expect = Expect::default();
    let mut main = String::new();
    let mut files: Vec<(String, String)> = Vec::new();
    let mut cited = false;
    let mut stream = false;
    for line in text.lines() {
        stream |= line.trim_end() == "; run: stream";
        if let Some(f) = line.strip_prefix("; --- file ") {
            files.push((f.trim().to_string(), String::new()));
            continue;
        }
        if line.starts_with("; TF5200 ") {
            cited = true;
        }
        if let Some(e) = line.strip_prefix("; expect:") {
            parse_expect(e.trim(), &mut expect).map_err(|m| format!("{name}: {m}: {line}"))?;
        }
        let into = match files.last_mut() {
            Some((_, t)) => t,
            None => &mut main,
        };
        into.push_str(line);
        into.push('\n');
    }
    if !cited {
        return Err(format!("{name}: no `; TF5200 …` line citing its page"));
    }
    Ok(Example {
        main,
        stream,
        files,
        expect,
    })
}

fn parse_expect(e: &str, x: &mut Expect) -> Result<(), String> {
    let (what, rest) = e.split_once(' ').unwrap_or((e, ""));
    let rest = rest.trim();
    match what {
        "end" => {
            for w in rest.split_whitespace() {
                let (a, v) = w.split_once('=').ok_or("axis=value expected")?;
                let a = a.chars().next().ok_or("axis expected")?;
                x.end.push((a, v.parse().map_err(|_| "number expected")?));
            }
        }
        "msg" => {
            let t = rest
                .strip_prefix('"')
                .and_then(|r| r.strip_suffix('"'))
                .ok_or("quoted text expected")?;
            x.msgs.push(t.to_string());
        }
        "error" => x.error = Some(rest.parse().map_err(|_| "error id expected")?),
        "warning" => x
            .warnings
            .push(rest.parse().map_err(|_| "warning id expected")?),
        "blocks" => {
            x.blocks = Some(
                rest.split_whitespace()
                    .map(n_number)
                    .collect::<Result<_, _>>()?,
            )
        }
        "runs" => {
            let mut w = rest.split_whitespace();
            let n = n_number(w.next().ok_or("block expected")?)?;
            let k = w.next().ok_or("count expected")?;
            x.runs.push((n, k.parse().map_err(|_| "count expected")?));
        }
        "dwell" => {
            let mut w = rest.split_whitespace();
            let n = n_number(w.next().ok_or("block expected")?)?;
            let s = w.next().ok_or("seconds expected")?;
            x.dwells
                .push((n, s.parse().map_err(|_| "seconds expected")?));
        }
        _ => return Err(format!("unknown expectation `{what}`")),
    }
    Ok(())
}

fn n_number(w: &str) -> Result<u64, String> {
    w.strip_prefix('N')
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| format!("block number N.. expected, found {w}"))
}

/// The channel the corpus runs in: the test rig's, file caching for 6 files of 6000 bytes
/// (TF5200 channel parameters, P-CHAN-00503/-00504: their parameterisation example), with the
/// fixture's channel and tool lists, and the axes X Y Z and U (the tracking axis of the
/// programming manual's G01 examples).
fn rig() -> Rig {
    let rig = Rig::with_cache(Some((6, 6000)), AXES_TOML);
    for f in ["channel1.lis", "tools.lis"] {
        std::fs::copy(
            corpus_dir().join("fixture").join(f),
            rig.dir.path().join("params").join(f),
        )
        .unwrap();
    }
    rig
}

/// Run one example; `Ok` when it behaves as its page says, else what differs.
fn check(name: &str, ex: &Example) -> Result<(), String> {
    let rig = rig();
    for (f, text) in &ex.files {
        rig.program(f, text);
    }
    let r = if ex.stream {
        let crlf = ex.main.replace('\n', "\r\n");
        rig.run("streaming.nc", Some(feeder(&crlf, 4096, 1)), MAX_TICKS)
    } else {
        rig.program(name, &ex.main);
        rig.run(name, None, MAX_TICKS)
    };
    let mut diffs = Vec::new();
    let errors = r.error_codes();
    match ex.expect.error {
        Some(code) if errors.first() != Some(&code) => {
            diffs.push(format!("error {code} expected, got {errors:?}"));
        }
        Some(_) => {}
        None if !errors.is_empty() => diffs.push(format!("errors {}", error_texts(&r))),
        None if r.finish != Some(Finish::Ended) => {
            diffs.push(format!("did not end: {:?}", r.finish));
        }
        None => {}
    }
    let warnings: Vec<u64> = r
        .of("warning")
        .iter()
        .filter_map(|w| w["code"].as_u64())
        .collect();
    for w in &ex.expect.warnings {
        if !warnings.contains(w) {
            diffs.push(format!("warning {w} expected, got {warnings:?}"));
        }
    }
    for &(axis, want) in &ex.expect.end {
        let got = position(&r, axis);
        if got.is_none_or(|g| (g - want).abs() > POSITION_TOL_MM) {
            diffs.push(format!("{axis}: {want} expected, got {got:?}"));
        }
    }
    let msgs: Vec<String> = r
        .of("message")
        .iter()
        .filter_map(|m| m["text"].as_str().map(String::from))
        .collect();
    if !ex.expect.msgs.is_empty() && msgs != ex.expect.msgs {
        diffs.push(format!(
            "messages {:?} expected, got {msgs:?}",
            ex.expect.msgs
        ));
    }
    let blocks = r.of("block");
    let numbers: Vec<u64> = blocks.iter().filter_map(|b| b["n"].as_u64()).collect();
    if let Some(want) = &ex.expect.blocks {
        if &numbers != want {
            diffs.push(format!("blocks {want:?} expected, got {numbers:?}"));
        }
    }
    for &(n, want) in &ex.expect.runs {
        let got = numbers.iter().filter(|&&k| k == n).count();
        if got != want {
            diffs.push(format!("N{n}: {want} runs expected, ran {got}"));
        }
    }
    for &(n, want) in &ex.expect.dwells {
        let i = blocks.iter().position(|b| b["n"].as_u64() == Some(n));
        let t = i.and_then(|i| {
            let start = blocks[i]["t"].as_f64()?;
            let next = blocks.get(i + 1).and_then(|b| b["t"].as_f64());
            let end = r.of("program_end").first().and_then(|e| e["t"].as_f64());
            Some(next.or(end)? - start)
        });
        if t.is_none_or(|t| (t - want).abs() > DWELL_TOL_S) {
            diffs.push(format!("N{n}: {want} s expected, lasted {t:?}"));
        }
    }
    if diffs.is_empty() {
        Ok(())
    } else {
        Err(diffs.join("; "))
    }
}

fn error_texts(r: &RunResult) -> String {
    r.of("error")
        .iter()
        .map(|e| format!("{} {}", e["code"], e["msg"]))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Where `axis` stands at the end, mm (`None`: no such axis in the channel).
/// Where the axis the channel names `axis` stands (a U axis drives a free slot: its name,
/// not the slot's letter, finds it).
fn position(r: &RunResult, axis: char) -> Option<f64> {
    r.machine.channels()[0]
        .report()
        .named_positions
        .into_iter()
        .find(|(a, _)| a.to_string() == axis.to_string())
        .map(|(_, v)| v)
}

/// `REFUSED.md`: `- file.nc: reason` lines (the rest of the file is prose).
fn refused() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(corpus_dir().join("REFUSED.md")).unwrap_or_default();
    text.lines()
        .filter_map(|l| l.strip_prefix("- "))
        .filter_map(|l| l.split_once(": "))
        .filter(|(f, _)| f.ends_with(".nc"))
        .map(|(f, r)| (f.trim_matches('`').to_string(), r.to_string()))
        .collect()
}

#[test]
fn manual_examples_behave_as_documented() {
    let refused = refused();
    let mut names: Vec<String> = std::fs::read_dir(corpus_dir())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".nc"))
        .collect();
    names.sort();
    let mut failures = Vec::new();
    let (mut good, mut listed) = (0, 0);
    for name in &names {
        let text = std::fs::read_to_string(corpus_dir().join(name)).unwrap();
        let outcome = parse_example(name, &text).and_then(|ex| check(name, &ex));
        match (outcome, refused.get(name)) {
            (Ok(()), None) => good += 1,
            (Err(why), Some(_)) => {
                listed += 1;
                println!("refused  {name}: {why}");
            }
            (Err(why), None) => failures.push(format!("{name} misbehaves: {why}")),
            (Ok(()), Some(reason)) => failures.push(format!(
                "{name} now behaves as documented: remove it from REFUSED.md ({reason})"
            )),
        }
    }
    for f in refused.keys().filter(|f| !names.contains(f)) {
        failures.push(format!("REFUSED.md lists {f}, which is not in the corpus"));
    }
    println!(
        "manual corpus: {good} of {} behave as documented, {listed} refused with reason",
        names.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
