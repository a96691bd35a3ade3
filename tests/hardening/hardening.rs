//! What a hostile or careless NC text, stream write or parameter file does to a channel: work
//! per tick bounded whatever the text, values that cannot be real refused with their numbers,
//! the same verdict from `check` and from a run, and the machine kept inside its soft limits.
//! docs/hardening.md says why each bound is where it is.

use std::process::Command as Process;
use std::time::Duration;

use crate::support::Rig;
use ncchannel::channel::{Channel, Finish, State};
use ncchannel::lang::{check_program, check_program_counted, parse_block, MAX_PROGRAM_DIAGS};
use ncchannel::machine::{Op, Reply};
use ncchannel::runtime::Tick;
use ncchannel::DECLARED_VALUES_PER_TICK;
use ncchannel::{VarClass, CLASS_BYTES};

fn tick(period: Duration, k: u64) -> Tick {
    Tick {
        index: k,
        period,
        time: period * k as u32,
        clock: ncchannel::runtime::Clock::Virtual,
    }
}

/// A channel run by hand: the channel, its tick period and the next tick.
struct Hand {
    channel: Channel,
    period: Duration,
    next: u64,
}

impl Hand {
    fn new(rig: &Rig) -> Hand {
        let (channel, period) = rig.channel();
        Hand {
            channel,
            period,
            next: 1,
        }
    }

    fn channel(&self) -> &Channel {
        &self.channel
    }

    /// Through the channel's door, as a client.
    fn apply(&mut self, op: Op) -> Reply {
        let t = self.now();
        self.channel.apply(&t, op)
    }

    fn now(&self) -> Tick {
        tick(self.period, self.next)
    }

    fn start(&mut self, program: &str) {
        assert_eq!(
            self.apply(Op::Start(program.into())),
            Reply::Command(Ok(()))
        );
    }

    /// One tick.
    fn step(&mut self) -> Option<Finish> {
        let t = self.now();
        self.next += 1;
        self.channel.step(&t);
        self.channel.take_finish()
    }

    /// Ticks until the program finishes (or `max` ticks): how it finished, after how many.
    fn run(&mut self, max: u64) -> (Option<Finish>, u64) {
        for k in 1..=max {
            if let Some(f) = self.step() {
                return (Some(f), k);
            }
        }
        (None, max)
    }

    fn error_code(&mut self) -> Option<u32> {
        self.channel().report().last_error.map(|e| e.code)
    }

    fn reset(&mut self) {
        self.apply(Op::Reset);
    }
}

/// Run `text` as a file program; its finish and the channel's last error number.
fn run_file(text: &str) -> (Option<Finish>, Option<u32>) {
    let rig = Rig::new();
    rig.program("t.nc", text);
    let mut h = Hand::new(&rig);
    h.start("t.nc");
    let (finish, _) = h.run(200_000);
    (finish, h.error_code())
}

/// The error numbers `check` finds in `text`.
fn check_codes(text: &str) -> Vec<u32> {
    check_program(text).iter().map(|d| d.code).collect()
}

fn long_name(k: usize) -> String {
    format!("{}{k}", "A".repeat(3_899))
}

/// The example: ten declarations of 100,000 values under 3,900-character names once
/// took one tick of 15 s and 3.95 GB. Now each name is stored once, each tick makes at most
/// about `DECLARED_VALUES_PER_TICK` values, and the V.L. class holds at most `CLASS_BYTES`.
#[test]
fn var_declarations_are_spread_over_ticks_and_bounded_in_bytes() {
    let rig = Rig::new();
    let decls: String = (0..10)
        .map(|k| format!("V.L.{}[100000] = 1.5\n", long_name(k)))
        .collect();
    rig.program(
        "decl.nc",
        &format!("#VAR\n{decls}#ENDVAR\nG01 X1 F1000\nM30\n"),
    );
    let mut h = Hand::new(&rig);
    h.start("decl.nc");
    h.step();
    let after_one = h.channel().report().var_bytes(VarClass::Local);
    assert!(
        after_one <= 2 * (DECLARED_VALUES_PER_TICK * 8 + 4_000 + 64),
        "one tick made {after_one} bytes of variables"
    );
    let (finish, _) = h.run(100_000);
    assert_eq!(finish, Some(Finish::Ended), "{:?}", h.error_code());
    // All ten were made by the program's end — in their name once each.
    let made = h.channel().report().var_bytes(VarClass::Local);
    assert!((10 * 800_000..=CLASS_BYTES).contains(&made), "{made}");
}

/// An eleventh such array does not fit the V.L. budget: 20967 (TF5200 "Memory for
/// variables limited"), in a bounded number of ticks.
#[test]
fn a_declaration_past_the_class_budget_is_20967() {
    let decls: String = (0..11)
        .map(|k| format!("V.L.{}[100000]\n", long_name(k)))
        .collect();
    let (finish, code) = run_file(&format!("#VAR\n{decls}#ENDVAR\nM30\n"));
    assert_eq!(finish, Some(Finish::Error));
    assert_eq!(code, Some(20967));
}

/// V.S. variables survive reset, so only their budget keeps them from growing program after
/// program: after a reset the class is as full as before, and a new array is still refused.
#[test]
fn self_retaining_variables_stay_bounded_across_resets() {
    let rig = Rig::new();
    let decls: String = (0..12).map(|k| format!("V.S.KEEP{k}[100000]\n")).collect();
    rig.program("fill.nc", &format!("#VAR\n{decls}#ENDVAR\nM30\n"));
    rig.program("more.nc", "#VAR\nV.S.ONE_MORE[100000]\n#ENDVAR\nM30\n");
    rig.program("again.nc", "#VAR\nV.S.KEEP0[100000] = 2\n#ENDVAR\nM30\n");
    let mut h = Hand::new(&rig);
    h.start("fill.nc");
    assert_eq!(h.run(100_000).0, Some(Finish::Error));
    assert_eq!(h.error_code(), Some(20967));
    let full = h.channel().report().var_bytes(VarClass::SelfRetaining);
    assert!(full <= CLASS_BYTES && full > CLASS_BYTES / 2, "{full}");
    h.reset();
    assert_eq!(
        h.channel().report().var_bytes(VarClass::SelfRetaining),
        full
    );
    h.start("more.nc");
    assert_eq!(h.run(100_000).0, Some(Finish::Error));
    assert_eq!(h.error_code(), Some(20967));
    // Declaring an existing V.S. array again replaces it: no growth, no error.
    h.reset();
    h.start("again.nc");
    assert_eq!(h.run(100_000).0, Some(Finish::Ended));
    assert_eq!(
        h.channel().report().var_bytes(VarClass::SelfRetaining),
        full
    );
}

/// `check` and a run read `#VAR` blocks with one function: what one accepts the other does,
/// and what one refuses the other refuses with the same number.
#[test]
fn check_and_run_agree_on_var_blocks() {
    let ok = "#VAR\nV.P.TABLE[10]\nV.L.GRID[3][4] = 2\n\n; comment\nV.S.KEEP = 1\nN10 #ENDVAR\nV.P.TABLE[9] = V.L.GRID[2][3]\nX[V.P.TABLE[9]] F100\nM30\n";
    assert_eq!(check_codes(ok), Vec::<u32>::new());
    assert_eq!(run_file(ok), (Some(Finish::Ended), None));
    for (decl, code) in [
        ("V.P.T[0]", 20200),
        ("V.P.T[2][2][2][2]", 20974),
        ("V.P.T[1000][1000]", 20967),
        ("V.E.X = 1", 20200),
        ("X10", 20200),
    ] {
        let text = format!("#VAR\n{decl}\n#ENDVAR\nM30\n");
        assert_eq!(check_codes(&text), [code], "check {decl}");
        assert_eq!(
            run_file(&text),
            (Some(Finish::Error), Some(code)),
            "run {decl}"
        );
    }
    // Writing outside a declared array is 21928.
    let text = "#VAR\nV.P.T[3]\n#ENDVAR\nV.P.T[3] = 1\nM30\n";
    assert_eq!(run_file(text), (Some(Finish::Error), Some(21928)));
}

/// Values that cannot be real: literals beyond f64 (which read as infinity), a radius or
/// centre beyond the data format, fractional tool numbers. Refused in `check` and in a run
/// with the same number; and a refused program ends (in ERROR) instead of running for ever.
#[test]
fn values_that_cannot_be_real_are_refused_in_check_and_run() {
    let nines = "9".repeat(309);
    for (block, code) in [
        (format!("G02 X10 Y0 R{nines} F100"), 20200),
        (format!("S{nines}"), 20200),
        (format!("T{nines}"), 20200),
        (format!("H{nines}"), 20200),
        (format!("D{nines}"), 20200),
        (format!("E{nines}"), 20200),
        (format!("P1 = {nines}"), 20200),
        ("G02 X10 Y0 I1000000000000000000 F100".to_string(), 20020),
        ("G02 X1 Y0 R1000000 F100".to_string(), 20054),
        ("T1.5".to_string(), 900132),
        ("D-2".to_string(), 900132),
        ("S-100".to_string(), 900132),
        ("F-1".to_string(), 20176),
    ] {
        let text = format!("{block}\nM30\n");
        assert_eq!(check_codes(&text), [code], "check {block:.40}");
        assert_eq!(
            run_file(&text),
            (Some(Finish::Error), Some(code)),
            "run {block:.40}"
        );
    }
    // Computed values go through the same check in the decoder.
    for (block, code) in [
        ("P1 = 10 ** 300\nG02 X10 Y0 R[P1] F100", 20054),
        ("P1 = 10 ** 18\nG02 X10 Y0 I[P1] F100", 20020),
        ("S[-5]", 900132),
        ("T[1 / 3]", 900132),
    ] {
        let text = format!("{block}\nM30\n");
        assert_eq!(
            run_file(&text),
            (Some(Finish::Error), Some(code)),
            "run {block}"
        );
    }
    // A full circle needs I/J/K: R with the end point on the start point is 20034.
    assert_eq!(
        run_file("G01 X5 Y5 F100\nG02 X5 Y5 R10\nM30\n"),
        (Some(Finish::Error), Some(20034))
    );
}

/// A literal of 309 digits that f64 can hold reads back from its canonical text; one it
/// cannot hold is 20200 at the literal — consistently, never infinity.
#[test]
fn long_literals_round_trip_or_are_refused() {
    let big = format!("X1{}", "0".repeat(308));
    let b = parse_block(&big).unwrap();
    let again = parse_block(&b.to_string()).unwrap();
    assert_eq!(b, again);
    let e = parse_block(&format!("X{}", "9".repeat(309))).unwrap_err();
    assert_eq!((e.code, e.col), (20200, 2));
    let e = parse_block(&format!("P1 = 2 * {}", "9".repeat(400))).unwrap_err();
    assert_eq!((e.code, e.col), (20200, 10));
}

/// A flat chain of 250 comparisons is within the parser's limits (height 256); its
/// canonical text brackets nothing, so it parses back (it once printed 250 nested brackets,
/// past the nesting limit of 64).
#[test]
fn canonical_text_of_a_long_chain_parses_back() {
    let chain: String = (0..250).map(|k| format!(" >= {}", k % 7)).collect();
    let line = format!("P1 = P2{chain}");
    let b = parse_block(&line).unwrap();
    let text = b.to_string();
    assert!(!text.contains('['), "{text}");
    assert_eq!(parse_block(&text).unwrap(), b);
    // Brackets stay where precedence needs them.
    for (written, canonical) in [
        ("P1 = [P2 + 3] * 4", "P1=[P2 + 3] * 4"),
        ("P1 = P2 - [P3 - P4]", "P1=P2 - [P3 - P4]"),
        ("P1 = [P2 - P3] - P4", "P1=P2 - P3 - P4"),
        ("P1 = [-2] ** 2", "P1=[-2] ** 2"),
        ("P1 = -[2] + 1", "P1=- 2 + 1"),
        ("P1 = -2 ** 2", "P1=-2 ** 2"),
        ("P1 = 2 ** 3 ** 2", "P1=2 ** 3 ** 2"),
        ("P1 = [2 ** 3] ** 2", "P1=[2 ** 3] ** 2"),
        ("P1 = NOT [P2 || P3]", "P1=NOT [P2 || P3]"),
        ("X[P1 * [2 + P2]]", "X[P1 * [2 + P2]]"),
    ] {
        let b = parse_block(written).unwrap();
        assert_eq!(b.to_string(), canonical, "{written}");
        assert_eq!(parse_block(canonical).unwrap(), b, "{canonical}");
    }
}

/// `G01 X5000 Y-7000` outside the ±1000 mm soft limits of runtime.toml: refused with 21897
/// before it moves; the error stops the axes on the earlier block's path (decoding runs
/// ahead of motion), never beyond it.
#[test]
fn soft_limits_refuse_the_block_before_it_moves() {
    let rig = Rig::new();
    rig.program("far.nc", "G01 X10 Y10 F6000\nG01 X5000 Y-7000\nM30\n");
    let mut h = Hand::new(&rig);
    h.start("far.nc");
    assert_eq!(h.run(200_000).0, Some(Finish::Error));
    assert_eq!(h.error_code(), Some(21897));
    let msg = h.channel().report().last_error.unwrap().msg.clone();
    assert!(msg.contains("axis X") && msg.contains("5000"), "{msg}");
    let p = h.channel().report().position;
    assert!(p[0] <= 10.0 + 1e-9 && p[1] <= 10.0 + 1e-9, "{p:?}");
    assert_eq!(h.channel().status().state, State::Error);
    // An arc whose end points are inside but whose circle passes X -1200 is refused too.
    assert_eq!(
        run_file("G01 X0 Y0 F6000\nG02 X0 Y0 I-600 J0\nM30\n"),
        (Some(Finish::Error), Some(21897))
    );
    // To the limit exactly is allowed, by a line and by an arc touching it.
    assert_eq!(
        run_file("G01 X990 Y0 F30000\nG03 X990 Y0 I5 J0\nG01 X1000 Y-1000\nM30\n"),
        (Some(Finish::Ended), None)
    );
    // Limits from runtime.toml: a machine with a 50 mm X travel refuses X60.
    let rig = Rig::with_runtime(
        "[[axes]]\nname = \"X\"\nsoft_limit_min_mm = 0.0\nsoft_limit_max_mm = 50.0\n\
         [[axes]]\nname = \"Y\"\n[[axes]]\nname = \"Z\"\n",
    );
    rig.program("t.nc", "G01 X50 F6000\nX60\nM30\n");
    let mut h = Hand::new(&rig);
    h.start("t.nc");
    assert_eq!(h.run(200_000).0, Some(Finish::Error));
    assert_eq!(h.error_code(), Some(21897));
    // The error stops the axes wherever the earlier block had brought them: never past 50.
    assert!(
        h.channel().report().position[0] <= 50.0,
        "{:?}",
        h.channel().report().position
    );
}

/// A stream write without CR LF while a *file* program runs is refused (the writer hears
/// 21476) and the file program goes on to its end; while the streaming program runs, the
/// same write aborts it (ISG FCT-C19 Data streaming: processing aborted).
#[test]
fn a_bad_stream_write_does_not_abort_a_running_file_program() {
    let rig = Rig::new();
    rig.program("file.nc", "G01 X10 F600\nG01 X0\nM30\n");
    let mut h = Hand::new(&rig);
    h.start("file.nc");
    for _ in 0..10 {
        h.step();
    }
    let r = h.apply(Op::WriteStream(b"N1 X1\n".as_slice().into()));
    let Reply::Stream(Err(e)) = r else {
        panic!("{r:?}")
    };
    assert_eq!(e.isg_code(), Some(21476));
    let (finish, _) = h.run(200_000);
    assert_eq!(finish, Some(Finish::Ended), "{:?}", h.error_code());
    assert!(h.channel().report().errors.is_empty());

    let mut h = Hand::new(&rig);
    h.start("streaming.nc");
    assert_eq!(
        h.apply(Op::WriteStream(b"G01 X10 F600\r\n".as_slice().into())),
        Reply::Stream(Ok(()))
    );
    for _ in 0..10 {
        h.step();
    }
    assert_ne!(
        h.apply(Op::WriteStream(b"N1 X1\n".as_slice().into())),
        Reply::Stream(Ok(()))
    );
    assert_eq!(h.run(1000).0, Some(Finish::Error));
    assert_eq!(h.error_code(), Some(21476));
}

/// 16 MiB of garbage: `check` lists the first findings and counts the rest, instead of
/// keeping millions (1.8 GB and 50 s for a list file once).
#[test]
fn check_bounds_what_it_collects() {
    let garbage = "a\n".repeat(8 << 20);
    let (list, diags) =
        ncchannel::params::list::parse_list(std::path::Path::new("bad.lis"), &garbage);
    assert!(list.entries.is_empty());
    assert_eq!(diags.len(), ncchannel::params::list::MAX_LIST_ERRORS + 1);
    assert!(
        diags.last().unwrap().message.contains(&format!(
            "{} more malformed line(s)",
            (8 << 20) - ncchannel::params::list::MAX_LIST_ERRORS
        )),
        "{}",
        diags.last().unwrap().message
    );
    let nc = "X\n".repeat(8 << 20);
    let (diags, all) = check_program_counted(&nc);
    assert_eq!(diags.len(), MAX_PROGRAM_DIAGS);
    assert_eq!(all, 8 << 20);
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

/// A FIFO given where a file is read (an NC program, runtime.toml) is refused with a line
/// that says so, instead of `check` waiting for ever for a writer.
#[cfg(unix)]
#[test]
fn check_refuses_a_fifo_instead_of_waiting_for_a_writer() {
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["prog.nc", "runtime.toml"] {
        let fifo = dir.path().join(name);
        let made = Process::new("mkfifo").arg(&fifo).status().expect("mkfifo");
        assert!(made.success());
        let mut child = Process::new(env!("CARGO_BIN_EXE_ncchannel"))
            .arg("check")
            .arg(&fifo)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("check starts");
        let until = std::time::Instant::now() + Duration::from_secs(60);
        while child.try_wait().expect("wait").is_none() {
            if std::time::Instant::now() > until {
                let _ = child.kill();
                panic!("check waited on the FIFO {name}");
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let out = child.wait_with_output().expect("output");
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert_ne!(out.status.code(), Some(0), "{text}");
        assert!(text.contains("not a regular file"), "{name}: {text}");
    }
}
