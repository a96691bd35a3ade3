//! The file cache (`#CACHE`, TF5200 File Caching) through the channel, in virtual time.

use crate::support as common;

use std::time::Duration;

use common::{channel_events, feeder, tick0, Rig};
use ncchannel::channel::{Channel, Finish, State};
use ncchannel::machine::{Op, Reply};
use ncchannel::runtime::Tick;
use ncchannel::FsLatency;
use serde_json::Value;

/// The seed-002 files the repository ships in `nc/`.
const SEED_FILES: [&str; 5] = [
    "cache_example.nc",
    "Laser_on.cyc",
    "Laser_off.cyc",
    "Macro.cyc",
    "Global.sub",
];

fn repo_nc(name: &str) -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("nc")
            .join(name),
    )
    .unwrap()
}

/// `(op, file)` of every `cache` event, in order.
fn cache_ops(events: &[Value]) -> Vec<(String, String)> {
    events
        .iter()
        .filter(|e| e["ev"] == "cache")
        .map(|e| {
            (
                e["op"].as_str().unwrap().to_string(),
                e["file"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect()
}

/// `(prog, text)` of every `block` event.
fn blocks(events: &[Value]) -> Vec<(String, String)> {
    events
        .iter()
        .filter(|e| e["ev"] == "block")
        .map(|e| {
            (
                e["prog"].as_str().unwrap().to_string(),
                e["text"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

/// Start `program` on a channel driven by hand and step it until it leaves ACTIVE.
fn run_program(c: &mut Channel, t: &mut Tick, program: &str) {
    assert_eq!(
        c.apply(t, Op::Start(program.to_string())),
        Reply::Command(Ok(()))
    );
    for _ in 0..1_000_000 {
        if !matches!(c.status().state, State::Active | State::Hold) {
            return;
        }
        c.step(t);
        next(t);
    }
    panic!("{program} did not finish");
}

fn next(t: &mut Tick) {
    t.index += 1;
    t.time += t.period;
}

fn ops(list: &[(&str, &str)]) -> Vec<(String, String)> {
    list.iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
}

#[test]
fn seed_002_example_runs_with_its_calls_served_from_the_cache() {
    let rig = Rig::with_cache(Some((6, 6000)), "");
    for f in SEED_FILES {
        rig.program(f, &repo_nc(f));
    }
    let r = rig.run("cache_example.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!(r.error_codes().is_empty(), "{}", r.log);
    assert_eq!(
        cache_ops(&r.events),
        ops(&[
            ("clear", "Laser_on.cyc"), // N1200: not cached, silent
            ("clear_all", ""),
            ("load", "Laser_on.cyc"),
            ("clear", "Laser_on.cyc"),
            ("load", "Macro.cyc"),
            ("load", "Laser_off.cyc"),
            ("refresh", "Laser_off.cyc"), // N1260
            ("load", "Global.sub"),
            // N3021: Laser_on.cyc was cleared at N1230, so it comes from the file system.
            ("hit", "Global.sub"),
            ("hit", "Macro.cyc"),
            ("hit", "Laser_off.cyc"),
        ])
    );
    let c = &r.machine.channels()[0];
    // Main program + five loads + the one uncached call (Laser_on.cyc); the three cached
    // calls open nothing.
    assert_eq!(c.report().store.opens, 7);
    assert_eq!(c.report().cache.hits, 3);
    let cached = c.report().cache.files;
    assert_eq!(cached, ["Macro.cyc", "Laser_off.cyc", "Global.sub"]);
    // Every called program ran, from its start to its M17.
    let b = blocks(&r.events);
    for (prog, last) in [
        ("Laser_on.cyc", "N120 M17"),
        ("Global.sub", "N40 M17"),
        ("Macro.cyc", "N70 M17"),
        ("Laser_off.cyc", "N60 M17"),
    ] {
        assert!(
            b.iter().any(|(p, t)| p == prog && t == last),
            "{prog} {last} missing"
        );
    }
    assert!(b.contains(&("cache_example.nc".into(), "N3050 M30".into())));
    // Laser_off.cyc retracted to Z5; the rectangle of Macro.cyc closed at X47 Y0.
    let pos = c.report().position;
    assert!((pos[0] - 47.0).abs() < 1e-6 && pos[1].abs() < 1e-6 && (pos[2] - 5.0).abs() < 1e-6);
}

#[test]
fn calls_after_the_load_never_touch_the_file_system() {
    let rig = Rig::new();
    rig.program("c.cyc", "P1=P1+@P1\nM17\n");
    let mut main = String::from("P1=0\n#CACHE LOAD[FILE=c.cyc]\n");
    for _ in 0..50 {
        main.push_str("L CYCLE [NAME=c.cyc @P1=2]\n");
    }
    main.push_str("$IF P1 != 100\nG1 X1 F100\n$ENDIF\nM30\n");
    rig.program("main.nc", &main);
    let r = rig.run("main.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let c = &r.machine.channels()[0];
    assert_eq!(c.report().store.opens, 2, "main program + the load");
    assert_eq!(c.report().cache.hits, 50);
    assert_eq!(c.report().position[0], 0.0, "each call ran: P1 = 50 × 2");
}

fn failing(rig: &Rig, main: &str) -> (u64, String, common::RunResult) {
    rig.program("main.nc", main);
    let r = rig.run("main.nc", None, 100_000);
    assert_eq!(r.finish, Some(Finish::Error), "{}", r.log);
    assert_eq!(r.machine.channels()[0].status().state, State::Error);
    let e = r.of("error")[0].clone();
    assert!(
        !r.block_texts().iter().any(|t| t == "G1 X10 F1000"),
        "nothing after the error runs"
    );
    (
        e["code"].as_u64().unwrap(),
        e["msg"].as_str().unwrap().to_string(),
        r,
    )
}

#[test]
fn cache_full_is_21562_and_a_refresh_needs_no_room() {
    let rig = Rig::new(); // 2 files of at most 200 bytes
    for f in ["a.cyc", "b.cyc", "c.cyc"] {
        rig.program(f, "M17\n");
    }
    rig.program(
        "ok.nc",
        "#CACHE LOAD[FILE=a.cyc]\n#CACHE LOAD[FILE=b.cyc]\n#CACHE LOAD[FILE=a.cyc]\nM30\n",
    );
    let r = rig.run("ok.nc", None, 10_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let (code, _, r) = failing(
        &rig,
        "#CACHE LOAD[FILE=a.cyc]\n#CACHE LOAD[FILE=b.cyc]\n#CACHE LOAD[FILE=c.cyc]\nG1 X10 F1000\nM30\n",
    );
    assert_eq!(code, 21562);
    assert_eq!(r.of("error")[0]["line"], 3);
    assert_eq!(r.machine.channels()[0].report().cache.files.len(), 2);
}

#[test]
fn file_not_found_is_21563() {
    let rig = Rig::new();
    let (code, msg, _) = failing(&rig, "#CACHE LOAD[FILE=nowhere.cyc]\nG1 X10 F1000\nM30\n");
    assert_eq!(code, 21563);
    assert!(msg.contains("nowhere.cyc"), "{msg}");
}

#[test]
fn file_larger_than_max_cache_size_is_21564_and_is_not_read() {
    let rig = Rig::new(); // max_cache_size 200
    let mut big = String::from("(padding");
    while big.len() < 200 {
        big.push('x');
    }
    big.push_str(")\nM17\n");
    rig.program("big.cyc", &big);
    rig.program("fits.cyc", &format!("({})\nM17\n", "y".repeat(193)));
    assert_eq!(
        std::fs::metadata(rig.nc().join("fits.cyc")).unwrap().len(),
        200
    );
    let (code, msg, r) = failing(
        &rig,
        "#CACHE LOAD[FILE=fits.cyc]\n#CACHE LOAD[FILE=big.cyc]\nG1 X10 F1000\nM30\n",
    );
    assert_eq!(code, 21564);
    assert!(msg.contains("big.cyc") && msg.contains("200"), "{msg}");
    let c = &r.machine.channels()[0];
    assert_eq!(
        c.report().store.opens,
        2,
        "main + fits.cyc; big.cyc is refused unread"
    );
    assert_eq!(c.report().cache.files, ["fits.cyc"]);
}

#[test]
fn cache_without_fct_use_cached_files_is_900160_naming_the_parameter() {
    let rig = Rig::with_cache(None, "");
    rig.program("a.cyc", "M17\n");
    for cmd in [
        "#CACHE LOAD[FILE=a.cyc]",
        "#CACHE CLEAR[FILE=a.cyc]",
        "#CACHE CLEAR ALL",
    ] {
        let (code, msg, _) = failing(&rig, &format!("{cmd}\nG1 X10 F1000\nM30\n"));
        assert_eq!(code, 900160, "{cmd}");
        assert!(msg.contains("FCT_USE_CACHED_FILES"), "{msg}");
    }
    // Calls work as ever, from the file system.
    rig.program("main.nc", "L CYCLE [NAME=a.cyc]\nM30\n");
    let r = rig.run("main.nc", None, 10_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
}

#[test]
fn invalid_cache_programming_is_21560() {
    let rig = Rig::new();
    rig.program("a.cyc", "M17\n");
    for cmd in [
        "#CACHE LOAD a.cyc",
        "#CACHE FETCH[FILE=a.cyc]",
        "#CACHE LOAD[NAME=a.cyc]",
        "#CACHE LOAD[FILE=]",
        "#CACHE CLEAR",
        "#CACHE CLEAR ALL now",
    ] {
        let (code, _, r) = failing(&rig, &format!("N10 {cmd}\nG1 X10 F1000\nM30\n"));
        assert_eq!(code, 21560, "{cmd}");
        assert_eq!(r.of("error")[0]["line"], 1);
        assert!(r.machine.channels()[0].report().cache.files.is_empty());
    }
}

#[test]
fn double_cache_programming_is_21561() {
    let rig = Rig::new();
    rig.program("a.cyc", "M17\n");
    rig.program("b.cyc", "M17\n");
    for cmd in [
        "#CACHE LOAD[FILE=a.cyc FILE=b.cyc]",
        "#CACHE LOAD[FILE=a.cyc][FILE=b.cyc]",
        "#CACHE CLEAR ALL[FILE=a.cyc]",
    ] {
        let (code, _, r) = failing(&rig, &format!("{cmd}\nG1 X10 F1000\nM30\n"));
        assert_eq!(code, 21561, "{cmd}");
        assert!(
            r.machine.channels()[0].report().cache.files.is_empty(),
            "{cmd}"
        );
    }
}

#[test]
fn the_cache_lasts_across_programs_until_a_reset() {
    let rig = Rig::new();
    rig.program("c.cyc", "G1 X5 F6000\nM17\n");
    rig.program("load.nc", "#CACHE LOAD[FILE=c.cyc]\nM30\n");
    rig.program("call.nc", "L CYCLE [NAME=c.cyc]\nG0 X0\nM30\n");
    let (mut channel, period) = rig.channel();
    let mut t = tick0(period);
    let c = &mut channel;
    run_program(c, &mut t, "load.nc");
    assert_eq!(c.report().cache.files.len(), 1);
    run_program(c, &mut t, "call.nc");
    assert_eq!(c.status().state, State::Ready);
    assert_eq!(
        c.report().store.opens,
        3,
        "load.nc, the load, call.nc: the call is a hit"
    );
    assert_eq!(c.report().cache.hits, 1);
    c.apply(&t, Op::Reset);
    assert!(
        c.report().cache.files.is_empty(),
        "a channel reset clears the cache"
    );
    run_program(c, &mut t, "call.nc");
    assert_eq!(c.status().state, State::Ready);
    assert_eq!(
        c.report().store.opens,
        5,
        "call.nc and c.cyc from the file system"
    );
    assert_eq!(c.report().cache.hits, 1);
}

#[test]
fn names_are_case_insensitive() {
    let rig = Rig::new();
    rig.program("Laser_On.CYC", "P1=P1+1\nM17\n");
    rig.program(
        "main.nc",
        "P1=0\n#CACHE LOAD[FILE=laser_on.cyc]\nL CYCLE [NAME=LASER_ON.CYC]\nL CYCLE [NAME=Laser_on.cyc]\n\
         #CACHE LOAD[FILE=LASER_ON.cyc]\n#CACHE CLEAR[FILE=lAsEr_On.CyC]\nL CYCLE [NAME=laser_on.cyc]\n\
         $IF P1 != 3\nG1 X10 F1000\n$ENDIF\nM30\n",
    );
    let r = rig.run("main.nc", None, 10_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(
        cache_ops(&r.events),
        ops(&[
            ("load", "laser_on.cyc"),
            ("hit", "LASER_ON.CYC"),
            ("hit", "Laser_on.cyc"),
            ("refresh", "LASER_ON.cyc"),
            ("clear", "lAsEr_On.CyC"),
        ])
    );
    let c = &r.machine.channels()[0];
    assert!(c.report().cache.files.is_empty());
    // main, load, refresh, and the last call from the file system.
    assert_eq!(c.report().store.opens, 4);
    assert_eq!(c.report().position[0], 0.0, "all three calls ran");
}

#[test]
fn cached_text_stays_until_refreshed_and_a_refresh_picks_up_the_changed_file() {
    let rig = Rig::new();
    rig.program("c.cyc", "G1 X1 F6000\nM17\n");
    rig.program("load.nc", "#CACHE LOAD[FILE=c.cyc]\nM30\n");
    rig.program("call.nc", "L CYCLE [NAME=c.cyc]\nM30\n");
    let (mut channel, period) = rig.channel();
    let mut t = tick0(period);
    let c = &mut channel;
    run_program(c, &mut t, "load.nc");
    std::fs::write(rig.nc().join("c.cyc"), "G1 X2 F6000\nM17\n").unwrap();
    // The cache holds what was loaded: the change on disk is not seen yet.
    run_program(c, &mut t, "call.nc");
    assert!((c.report().position[0] - 1.0).abs() < 1e-9);
    run_program(c, &mut t, "load.nc");
    run_program(c, &mut t, "call.nc");
    assert!((c.report().position[0] - 2.0).abs() < 1e-9, "refreshed");
    let ev = channel_events(c);
    assert_eq!(
        cache_ops(&ev),
        ops(&[
            ("load", "c.cyc"),
            ("hit", "c.cyc"),
            ("refresh", "c.cyc"),
            ("hit", "c.cyc"),
        ])
    );
    assert_eq!(c.report().store.opens, 6, "four main programs, two loads");
}

#[test]
fn a_refresh_while_the_cycle_runs_leaves_the_running_call_on_the_old_text() {
    let rig = Rig::new();
    // Version 1 refreshes its own cache entry halfway, after the file has been rewritten.
    rig.program(
        "c.cyc",
        "G1 X10 F6000\n#FLUSH WAIT\n#CACHE LOAD[FILE=c.cyc]\nG1 Y1\nM17\n",
    );
    rig.program(
        "main.nc",
        "#CACHE LOAD[FILE=c.cyc]\nL CYCLE [NAME=c.cyc]\nL CYCLE [NAME=c.cyc]\nM30\n",
    );
    let (mut channel, period) = rig.channel();
    let mut t = tick0(period);
    let c = &mut channel;
    common::start(c, &t, "main.nc");
    // The X move takes 100 ms; #FLUSH WAIT holds decoding until it is done.
    for _ in 0..20 {
        c.step(&t);
        next(&mut t);
    }
    assert!(c.report().position[0] > 0.0 && c.report().position[0] < 10.0);
    std::fs::write(rig.nc().join("c.cyc"), "G1 X20 F6000\nG1 Y2\nM17\n").unwrap();
    for _ in 0..100_000 {
        if c.status().state != State::Active {
            break;
        }
        c.step(&t);
        next(&mut t);
    }
    assert_eq!(c.status().state, State::Ready);
    let ev = channel_events(c);
    let cyc: Vec<String> = blocks(&ev)
        .into_iter()
        .filter(|(p, _)| p == "c.cyc")
        .map(|(_, t)| t)
        .collect();
    assert_eq!(
        cyc,
        [
            // First call: the old text to its end, although it refreshed itself.
            "G1 X10 F6000",
            "#FLUSH WAIT",
            "#CACHE LOAD[FILE=c.cyc]",
            "G1 Y1",
            "M17",
            // Second call: the new text.
            "G1 X20 F6000",
            "G1 Y2",
            "M17",
        ]
    );
    assert_eq!(
        cache_ops(&ev),
        ops(&[
            ("load", "c.cyc"),
            ("hit", "c.cyc"),
            ("refresh", "c.cyc"),
            ("hit", "c.cyc"),
        ])
    );
}

#[test]
fn a_streamed_program_calls_from_the_cache() {
    let rig = Rig::new();
    rig.program("c.cyc", "G91 G1 X[@P1] F6000\nG90\nM17\n");
    let r = rig.run(
        "streaming.nc",
        Some(feeder(
            "N10 #CACHE LOAD[FILE=c.cyc]\nN20 L CYCLE [NAME=c.cyc @P1=3]\nN30 L CYCLE [NAME=C.CYC @P1=4]\nN40 M30\n",
            992,
            1,
        )),
        100_000,
    );
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(
        cache_ops(&r.events),
        ops(&[("load", "c.cyc"), ("hit", "c.cyc"), ("hit", "C.CYC")])
    );
    let c = &r.machine.channels()[0];
    assert_eq!(c.report().store.opens, 1, "only the load reads a file");
    assert!((c.report().position[0] - 7.0).abs() < 1e-9);
}

#[test]
fn a_stream_called_from_a_file_program_uses_the_cache_the_file_loaded() {
    let rig = Rig::new();
    rig.program("sub.nc", "G1 Y5 F6000\nM17\n");
    rig.program("main.nc", "#CACHE LOAD[FILE=sub.nc]\nL streaming.nc\nM30\n");
    let r = rig.run(
        "main.nc",
        Some(feeder("N100 L sub.nc\nN110 G1 X3 F6000\nM17\n", 992, 1)),
        100_000,
    );
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let c = &r.machine.channels()[0];
    assert_eq!(c.report().store.opens, 2, "main.nc and the load");
    assert_eq!(c.report().cache.hits, 1);
    let pos = c.report().position;
    assert!((pos[0] - 3.0).abs() < 1e-9 && (pos[1] - 5.0).abs() < 1e-9);
}

/// A main program calling a motion-less cycle `calls` times, cached or not.
fn latency_run(runtime: &str, cached: bool, calls: usize) -> (u64, Duration, u64) {
    let rig = Rig::with_cache(Some((2, 200)), runtime);
    rig.program("c.cyc", "P1=P1+1\nM17\n");
    let mut main = String::from("P1=0\n");
    if cached {
        main.push_str("#CACHE LOAD[FILE=c.cyc]\n");
    }
    for _ in 0..calls {
        main.push_str("L CYCLE [NAME=c.cyc]\n");
    }
    main.push_str("M30\n");
    rig.program("main.nc", &main);
    let r = rig.run("main.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let s = r.machine.channels()[0].report().store;
    (s.opens, s.latency, r.ticks)
}

#[test]
fn fs_latency_costs_uncached_calls_simulated_time_and_cached_ones_none() {
    // 50 ms per open, 1 ms ticks.
    let rt = "fs_latency_us = 50000\n";
    let (opens, latency, ticks) = latency_run(rt, false, 10);
    assert_eq!(opens, 11);
    assert_eq!(latency, Duration::from_millis(550));
    assert!((550..600).contains(&ticks), "{ticks} ticks");
    let (opens, latency, ticks) = latency_run(rt, true, 10);
    assert_eq!(opens, 2, "main program and the load");
    assert_eq!(latency, Duration::from_millis(100));
    assert!((100..130).contains(&ticks), "{ticks} ticks");
    // Without latency neither waits.
    let (_, latency, ticks) = latency_run("", false, 10);
    assert_eq!(latency, Duration::ZERO);
    assert!(ticks < 10, "{ticks} ticks");
}

#[test]
fn fs_latency_below_a_tick_is_accounted_in_fractions_of_ticks() {
    // 200 µs + 1000 µs per KiB: c.cyc (12 bytes) costs 211.7 µs, so between four and five
    // reads complete per 1 ms tick, not one per tick.
    let rt = "fs_latency_us = 200\nfs_latency_us_per_kib = 1000\n";
    let (opens, latency, ticks) = latency_run(rt, false, 100);
    assert_eq!(opens, 101);
    let fs = FsLatency::from_us(200, 1000);
    let main_bytes = 5 + 100 * 21 + 4;
    assert_eq!(latency, fs.cost(12) * 100 + fs.cost(main_bytes));
    let ms = latency.as_millis() as u64; // 23
    assert!(
        (ms..ms + 3).contains(&ticks),
        "{ticks} ticks for {latency:?}"
    );
}

#[test]
fn motion_keeps_running_while_a_read_is_pending() {
    // 300 ms per open; the X move takes 1 s. Decoding the call waits for its read while the
    // move runs: 0.3 s (main program) + 1 s of motion, not 0.3 + 0.3 + 1. `#FLUSH CONTINUE`
    // releases the move at once (else the planner holds it for the window or program end).
    let rig = Rig::with_cache(Some((2, 200)), "fs_latency_us = 300000\n");
    rig.program("c.cyc", "P1=1\nM17\n");
    rig.program(
        "main.nc",
        "G1 X10 F600\n#FLUSH CONTINUE\nL CYCLE [NAME=c.cyc]\nM30\n",
    );
    let r = rig.run("main.nc", None, 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert!((1300..1400).contains(&r.ticks), "{} ticks", r.ticks);
    let first = r.of("block")[0]["t"].as_f64().unwrap();
    assert!((first - 0.3).abs() < 0.002, "first block at {first} s");
}

#[test]
fn the_channel_list_can_switch_caching_on() {
    let rig = Rig::with_cache(None, "");
    std::fs::write(
        rig.dir.path().join("params/channel1.lis"),
        "streaming_prog_file streaming.nc\nconfiguration.decoder.function FCT_USE_CACHED_FILES\n\
         configuration.decoder.max_cache_number 1\n",
    )
    .unwrap();
    rig.program("a.cyc", "M17\n");
    rig.program("b.cyc", "M17\n");
    rig.program(
        "main.nc",
        "#CACHE LOAD[FILE=a.cyc]\nL CYCLE [NAME=a.cyc]\n#CACHE LOAD[FILE=b.cyc]\nM30\n",
    );
    let r = rig.run("main.nc", None, 10_000);
    // One file allowed by the channel list: the second load is 21562.
    assert_eq!(r.error_codes(), [21562], "{}", r.log);
    assert_eq!(r.machine.channels()[0].report().cache.hits, 1);
}

#[test]
fn run_reports_file_system_opens_bytes_and_cache_hits() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = tempfile::tempdir().unwrap();
    let report = out.path().join("r.json");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["run", "cache_example.nc", "--params"])
        .arg(root.join("params/startup.lis"))
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let human = String::from_utf8_lossy(&st.stdout);
    assert!(human.contains("files:      7 opens"), "{human}");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let size = |f: &str| std::fs::metadata(root.join("nc").join(f)).unwrap().len();
    // Main program, the five loads (Laser_off.cyc twice) and the uncached Laser_on.cyc call.
    let bytes = size("cache_example.nc")
        + 2 * size("Laser_on.cyc")
        + size("Macro.cyc")
        + 2 * size("Laser_off.cyc")
        + size("Global.sub");
    assert_eq!(v["files"]["opens"], 7);
    assert_eq!(v["files"]["bytes_read"], bytes);
    assert_eq!(v["files"]["cache_hits"], 3);
    assert_eq!(v["files"]["latency_s"], 0.0);
}
