//! What hostile or careless NC text and command lines do to a channel: circles no machine
//! can run, literals beyond f64, moves beyond the software limits, `serve --seconds` that is
//! no duration. Each is refused with its number, before anything moves, in `run` and `check` alike.

mod common;

use std::process::Command as Process;

use common::Rig;
use ncchannel::channel::Finish;
use ncchannel::lang::{check_program, codes, parse_block};

#[test]
fn circles_no_machine_can_run_are_refused_and_the_program_ends() {
    let nines = "9".repeat(300);
    for (arc, what) in [
        (format!("G02 X10 Y0 R{nines}"), "R of 300 digits"),
        ("G02 X0 Y0 I1000000000000000000".to_string(), "I of 1e18 mm"),
        ("G03 X0 Y0 J-2000000".to_string(), "a 2 km circle"),
    ] {
        let rig = Rig::new();
        rig.program("arc.nc", &format!("G1 X0 Y0 F1000\n{arc}\nM30\n"));
        // Bounded: the refused circle would never end.
        let r = rig.run("arc.nc", None, 200_000);
        assert_eq!(r.finish, Some(Finish::Error), "{what}: {}", r.log);
        assert_eq!(
            r.error_codes(),
            [u64::from(codes::ARC_INCONSISTENT)],
            "{what}"
        );
        assert!(
            r.log.contains("not a circle a machine can run"),
            "{what}: {}",
            r.log
        );
        assert!(r.position('X').is_finite() && r.position('Y').is_finite());
    }
}

#[test]
fn a_literal_beyond_f64_is_20200_in_every_word_and_expression() {
    let huge = "9".repeat(309);
    for line in [
        format!("G1 X{huge}"),
        format!("S{huge}"),
        format!("T{huge}"),
        format!("H{huge}"),
        format!("D{huge}"),
        format!("P1 = {huge} + 1"),
    ] {
        let e = parse_block(&line).expect_err(&line);
        assert_eq!(e.code, codes::SYNTAX, "{line}: {}", e.message);
        assert!(e.message.contains("308"), "{line}: {}", e.message);
        let d = check_program(&format!("{line}\nM30\n"));
        assert_eq!(d.len(), 1, "check {line}: {d:?}");
        assert_eq!(d[0].code, codes::SYNTAX);
    }
    // 308 digits is still a number (about 1e307).
    assert!(parse_block(&format!("P1 = {}", "9".repeat(308))).is_ok());
}

#[test]
fn a_move_beyond_the_software_limits_is_an_error_before_it_starts() {
    // The shipped default limits are ±1000 mm. The offending block is refused when it enters
    // the lookahead, while the channel still runs towards X10 Y10: the error stops the channel
    // there, and the refused move never starts.
    for (block, axis) in [
        ("G01 X5000 Y-7000", 'X'),
        ("G0 Z-1000.001", 'Z'),
        // Both end points inside, the arc's far side (X 1010) outside.
        ("G02 X10 Y10 I500 J0", 'X'),
    ] {
        let rig = Rig::new();
        rig.program("far.nc", &format!("G1 X10 Y10 F6000\n{block}\nM30\n"));
        let r = rig.run("far.nc", None, 2_000_000);
        assert_eq!(r.finish, Some(Finish::Error), "{block}: {}", r.log);
        assert_eq!(r.error_codes(), [u64::from(codes::SOFT_LIMIT)], "{block}");
        let err = r.of("error")[0].clone();
        assert_eq!(err["prog"], "far.nc", "{block}");
        assert_eq!(err["line"], 2, "{block}");
        assert!(
            r.log.contains(&format!("axis {axis} would move to")),
            "{block}: {}",
            r.log
        );
        for a in ['X', 'Y', 'Z'] {
            let v = r.position(a);
            assert!((0.0..=10.0).contains(&v), "{block}: {a} at {v}");
        }
    }
    // Reaching a limit exactly is allowed.
    let rig = Rig::new();
    rig.program("edge.nc", "G0 X1000 Y0\nG02 X1000 Y0 I-500 J0 F6000\nM30\n");
    let r = rig.run("edge.nc", None, 5_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
}

#[test]
fn serve_seconds_out_of_range_is_a_usage_error_not_a_panic() {
    // (`inf` is allowed: it runs until a signal, as no value does.)
    for bad in ["NaN", "-1", "-inf"] {
        let out = Process::new(env!("CARGO_BIN_EXE_ncchannel"))
            .args([
                "serve",
                "--bind",
                "127.0.0.1:0",
                &format!("--seconds={bad}"),
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "--seconds {bad}: {err}");
        assert!(!err.contains("panicked"), "--seconds {bad}: {err}");
        assert!(err.contains("--seconds"), "--seconds {bad}: {err}");
    }
}

#[test]
fn a_bare_lf_written_to_the_stream_does_not_abort_a_running_file_program() {
    // A file program runs; a client writes a packet with a bare LF into the stream interface.
    // The write is refused (21476, a warning: no program reads the stream), the file program
    // runs to its end.
    let rig = Rig::new();
    rig.program("file.nc", "G1 X10 F600\nG1 X20\nM30\n");
    let raw = ncchannel::feeder::Feeder::new(b"N1 X1\n".to_vec(), 992, 1, true).unwrap();
    let r = rig.run("file.nc", Some(raw), 200_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    assert_eq!(r.position('X'), 20.0);
    let warned = r
        .of("warning")
        .iter()
        .any(|w| w["code"].as_u64() == Some(u64::from(codes::NO_LINE_END)));
    assert!(warned, "{}", r.log);
    assert!(r.error_codes().is_empty(), "{}", r.log);
}
