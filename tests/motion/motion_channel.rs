//! Motion through a whole channel and through `ncchannel run`: parameter files on disk, NC text
//! decoded, streamed programs with slow and fast feeders, `#FLUSH CONTINUE`, interrupts and
//! resumes, zero offsets from the zero-offset list, `--plot`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use ncchannel::channel::{Channel, State};
use ncchannel::machine::Op;
use ncchannel::report::event::{EventKind, EventLog};
use ncchannel::runtime::Tick;

use crate::support::{start, write, WRITTEN};

const PERIOD: Duration = Duration::from_millis(1);

/// A parameter set in a temp folder: params/{startup.lis,channel1.lis,runtime.toml}, nc/.
struct Setup {
    dir: tempfile::TempDir,
}

impl Setup {
    fn new(extra_startup: &str, runtime: &str) -> Setup {
        let dir = tempfile::tempdir().unwrap();
        let params = dir.path().join("params");
        std::fs::create_dir_all(&params).unwrap();
        std::fs::create_dir_all(dir.path().join("nc")).unwrap();
        std::fs::write(
            params.join("startup.lis"),
            format!(
                "kanal_anzahl 1\nsda_mds[0] channel1.lis\npfad[0].prg[0] ../nc\n\
                 pfad[0].typ[0] 0x03\npfad[0].prioritaet[0] 0\n{extra_startup}"
            ),
        )
        .unwrap();
        std::fs::write(
            params.join("channel1.lis"),
            "streaming_prog_file streaming.nc\n",
        )
        .unwrap();
        std::fs::write(params.join("runtime.toml"), runtime).unwrap();
        Setup { dir }
    }
    fn startup(&self) -> PathBuf {
        self.dir.path().join("params/startup.lis")
    }
    fn write(&self, rel: &str, text: &str) -> PathBuf {
        let p = self.dir.path().join(rel);
        std::fs::write(&p, text).unwrap();
        p
    }
    fn channel(&self) -> Channel {
        let config = ncchannel::params::load(&self.startup()).unwrap();
        ncchannel::channels(&config, true, &ncchannel::Loader::start())
            .unwrap()
            .remove(0)
    }
}

fn tick(k: u64) -> Tick {
    Tick {
        index: k,
        period: PERIOD,
        time: PERIOD * k as u32,
        clock: ncchannel::runtime::Clock::Virtual,
    }
}

/// Run a streamed program: `writes` are (tick, text) written into the stream interface.
/// Returns the channel and every event kind with its tick.
fn run_stream(
    s: &Setup,
    writes: &[(u64, &str)],
    max_ticks: u64,
) -> (Channel, Vec<(u64, EventKind)>, Vec<f64>) {
    let mut c = s.channel();
    start(&mut c, &tick(0), "streaming.nc");
    let mut events = Vec::new();
    let mut velocity = Vec::new();
    for k in 0..max_ticks {
        let t = tick(k);
        for (at, text) in writes {
            if *at == k {
                assert_eq!(write(&mut c, &t, text.as_bytes()), WRITTEN);
            }
        }
        c.step(&t);
        velocity.push(c.status().velocity_mm_per_s);
        events.extend(
            c.events_mut()
                .events()
                .iter()
                .map(|e| (e.tick, e.kind.clone())),
        );
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active && c.status().state != State::Hold {
            break;
        }
    }
    (c, events, velocity)
}

/// Events of `k`'s kind (fields not compared).
fn count(events: &[(u64, EventKind)], k: &EventKind) -> usize {
    let d = std::mem::discriminant(k);
    events
        .iter()
        .filter(|(_, e)| std::mem::discriminant(e) == d)
        .count()
}

fn blocks(events: &[(u64, EventKind)]) -> Vec<(u64, Option<u64>)> {
    events
        .iter()
        .filter_map(|(t, e)| match e {
            EventKind::Block { n, .. } => Some((*t, *n)),
            _ => None,
        })
        .collect()
}

#[test]
fn flush_continue_next_block_in_time_no_stop_late_one_interrupt() {
    let s = Setup::new("", "");
    let first = "N10 G1 X10 F1000\r\n#FLUSH CONTINUE\r\n";
    let next = "N20 X20\r\n#FLUSH CONTINUE\r\n";
    let end = "N30 M30\r\n";
    // N10 takes about 0.61 s at F1000. In time: N20 arrives at 0.3 s.
    let (c, ev, v) = run_stream(&s, &[(1, first), (300, next), (1500, end)], 5000);
    assert_eq!(
        count(&ev, &EventKind::Interrupt { held: 0 }),
        1,
        "only after N20, waiting for M30"
    );
    let b = blocks(&ev);
    let t10 = b.iter().find(|x| x.1 == Some(10)).unwrap().0 as usize;
    let t20 = b.iter().find(|x| x.1 == Some(20)).unwrap().0 as usize;
    let min_v = v[t10 + 100..t20 + 100]
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    assert!(
        min_v > 16.0,
        "slowed to {min_v} mm/s at the N10/N20 junction"
    );
    assert_eq!(c.report().position[0], 20.0);
    assert_eq!(c.report().stats.interrupts, 1);

    // Late: N20 arrives at 1.0 s, after N10 has stopped: an interrupt, then a resume.
    let (c, ev, _) = run_stream(&s, &[(1, first), (1000, next), (2500, end)], 6000);
    assert_eq!(count(&ev, &EventKind::Interrupt { held: 0 }), 2);
    assert_eq!(count(&ev, &EventKind::Resume), 2);
    let first_interrupt = ev
        .iter()
        .find(|e| e.1 == EventKind::Interrupt { held: 0 })
        .unwrap()
        .0;
    assert!((600..1000).contains(&first_interrupt), "{first_interrupt}");
    let resume = ev.iter().find(|e| e.1 == EventKind::Resume).unwrap().0;
    assert_eq!(resume, 1000, "resumes when N20 starts");
    assert_eq!(c.report().position[0], 20.0);
    assert!(ev.iter().any(|e| e.1
        == EventKind::ProgramEnd {
            prog: "streaming.nc".into(),
            end: ncchannel::report::event::ProgramEndKind::M30
        }));
}

#[test]
fn without_flush_blocks_wait_in_the_window_and_the_program_end_releases_them() {
    let s = Setup::new("", "[planner]\nlookahead_blocks = 8\n");
    let text: String = (1..=3)
        .map(|i| format!("N{i} G1 X{} F3000\r\n", i * 5))
        .collect();
    let (c, ev, _) = run_stream(&s, &[(1, &text), (400, "M30\r\n")], 3000);
    let b = blocks(&ev);
    // Held: nothing takes effect until M30 arrives; the standstill is an interrupt that says
    // the window holds the three blocks.
    assert!(b.iter().all(|x| x.0 >= 400), "{b:?}");
    let held: Vec<u64> = ev
        .iter()
        .filter_map(|e| match e.1 {
            EventKind::Interrupt { held } => Some(held),
            _ => None,
        })
        .collect();
    assert_eq!(held, vec![3]);
    assert_eq!(c.report().position[0], 15.0);
}

#[test]
fn hold_is_not_an_interrupt_and_program_end_is_not_one_either() {
    let s = Setup::new("", "");
    let mut c = s.channel();
    s.write("nc/long.nc", "N10 G1 X100 F6000\nN20 M30\n");
    start(&mut c, &tick(0), "long.nc");
    let mut events = Vec::new();
    for k in 1..3000u64 {
        let t = tick(k);
        if k == 300 {
            c.apply(&t, Op::Hold);
        }
        if k == 800 {
            c.apply(&t, Op::Resume);
        }
        c.step(&t);
        if k == 790 {
            assert_eq!(c.status().state, State::Hold);
            assert_eq!(c.status().velocity_mm_per_s, 0.0);
        }
        events.extend(c.events_mut().events().iter().map(|e| e.kind.clone()));
        c.events_mut().flush_to(&mut EventLog::disabled());
    }
    assert!(!events
        .iter()
        .any(|e| matches!(e, EventKind::Interrupt { .. })));
    assert_eq!(c.status().state, State::Ready);
    assert_eq!(c.report().position[0], 100.0);
}

#[test]
fn arcs_in_nc_text_end_exactly_and_inconsistent_ones_are_errors() {
    let s = Setup::new("", "");
    s.write(
        "nc/arcs.nc",
        "N10 G17 G90 G1 X10 Y0 F3000\n\
         N20 G3 X-10 Y0 I-10 J0\n\
         N30 G2 X10 Y0 R10\n\
         N40 G18 G3 X0 Z10 K10 Y5\n\
         N50 G19 G2 Y-5 Z20 R10\n\
         N60 M30\n",
    );
    let mut c = s.channel();
    start(&mut c, &tick(0), "arcs.nc");
    for k in 1..20_000 {
        c.step(&tick(k));
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    let p = c.report().position;
    assert_eq!((p[0], p[1], p[2]), (0.0, -5.0, 20.0));

    s.write(
        "nc/bad.nc",
        "N10 G1 X10 Y0 F3000\nN20 G3 X0 Y10.5 I-10 J0\nM30\n",
    );
    let mut c = s.channel();
    start(&mut c, &tick(0), "bad.nc");
    for k in 1..5000 {
        c.step(&tick(k));
    }
    assert_eq!(c.status().state, State::Error);
    assert_eq!(c.report().last_error.unwrap().code, 900130);
}

#[test]
fn zero_offsets_from_the_list_named_in_the_startup_list() {
    let s = Setup::new("zero_offset_list zero.lis\n", "");
    s.write(
        "params/zero.lis",
        "# G54 (group 1): X 10 mm, Y -2.5 mm; G55 (group 2): Z 1 mm\n\
         np_grp[1].achse[0].versch 100000\n\
         np_grp[1].achse[1].versch -25000\n\
         np_grp[2].achse[2].versch 10000\n",
    );
    s.write(
        "nc/np.nc",
        "N10 G54 G90 G0 X0 Y0\nN20 #FLUSH WAIT\nN30 G55 G0 X1 Z0\nN40 G53 G0 Y7\nM30\n",
    );
    let mut c = s.channel();
    start(&mut c, &tick(0), "np.nc");
    let mut after_n10 = None;
    for k in 1..10_000u64 {
        c.step(&tick(k));
        let ev: Vec<EventKind> = c
            .events_mut()
            .events()
            .iter()
            .map(|e| e.kind.clone())
            .collect();
        c.events_mut().flush_to(&mut EventLog::disabled());
        if ev.iter().any(|e| matches!(e, EventKind::Flush { .. })) {
            after_n10 = Some(c.report().position);
        }
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    let p = after_n10.unwrap();
    assert_eq!((p[0], p[1]), (10.0, -2.5));
    let p = c.report().position;
    assert_eq!((p[0], p[1], p[2]), (1.0, 7.0, 1.0));

    // A list that cannot be read is refused at start-up, pointing at the start-up entry.
    let s = Setup::new("zero_offset_list missing.lis\n", "");
    let e = ncchannel::params::load(&s.startup()).unwrap_err();
    let d = &e.errors()[0];
    assert!(d.message.contains("zero-offset list"), "{}", d.message);
    assert_eq!(d.line, 6);
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
}

fn run_report(s: &Setup, stream: &Path, extra: &[&str]) -> serde_json::Value {
    let report = s.dir.path().join("report.json");
    let out = bin()
        .arg("run")
        .arg("--params")
        .arg(s.startup())
        .arg("--stream")
        .arg(stream)
        .arg("--report")
        .arg(&report)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap()
}

#[test]
fn run_slow_feeder_interrupts_fast_feeder_does_not_and_plot_marks_them() {
    let s = Setup::new("", "");
    // 200 blocks of 1 mm at F6000: 10 ms each.
    let mut text = String::from("G90 G1 F6000\n");
    for i in 1..=200 {
        text.push_str(&format!("N{i} X{i}\n"));
    }
    text.push_str("M30\n");
    let prog = s.write("prog.txt", &text);

    let fast = run_report(&s, &prog, &[]);
    assert_eq!(fast["outcome"], "ended");
    assert_eq!(fast["interrupts"], 0);
    assert_eq!(fast["position"]["X"], 200.0);

    // One ~24-byte packet every 30 ticks: a block every 30 ms, slower than motion needs.
    let plot = s.dir.path().join("p.svg");
    let slow = run_report(
        &s,
        &prog,
        &[
            "--packet",
            "24",
            "--every",
            "30",
            "--plot",
            plot.to_str().unwrap(),
        ],
    );
    assert_eq!(slow["outcome"], "ended");
    let n = slow["interrupts"].as_u64().unwrap();
    assert!(n >= 2, "{n}");
    assert_eq!(slow["position"]["X"], 200.0);
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg"));
    assert_eq!(
        svg.matches("<circle").count() as u64,
        n,
        "one mark per interrupt"
    );
    assert!(svg.contains(&format!("{n} interrupt(s)")));
}

#[test]
fn run_short_segments_at_f6000_without_interrupts_when_the_stream_keeps_up() {
    let s = Setup::new("", "");
    // 2000 segments of 0.1 mm at F6000: 1,000 blocks per second at full feed.
    let mut text = String::from("G90 G1 F6000\n");
    for i in 1..=2000 {
        text.push_str(&format!("X{:.1}\n", i as f64 * 0.1));
    }
    text.push_str("M30\n");
    let prog = s.write("seg.txt", &text);
    let r = run_report(&s, &prog, &[]);
    assert_eq!(r["outcome"], "ended");
    assert_eq!(r["interrupts"], 0);
    assert_eq!(r["position"]["X"], 200.0);
    // 200 mm at close to 100 mm/s: about 2 s, certainly under 2.5 s.
    let t = r["time_s"].as_f64().unwrap();
    assert!(t < 2.5, "{t}");
}

#[test]
fn check_list_file_recognises_a_zero_offset_list() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("zero.lis");
    std::fs::write(
        &p,
        "np_grp[1].achse[0].versch 1.5\nnp_grp[1].achse[1].versch 100\n",
    )
    .unwrap();
    let d = ncchannel::params::check_list_file(&p);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!((d[0].line, d[0].col), (1, 27));
    assert!(d[0].message.contains("0.1 µm"), "{}", d[0].message);
}

#[test]
fn m5_after_the_last_motion_of_a_paused_stream_takes_effect_when_the_motion_ends() {
    let s = Setup::new("", "[planner]\nlookahead_blocks = 4\n");
    // Six moves fill the window (4) and are released; M5 and a dwell follow, then the stream
    // pauses for 3 s before M30.
    let mut text: String = (1..=6)
        .map(|i| format!("N{i} G1 X{} F3000\r\n", i * 5))
        .collect();
    text.push_str("N7 M5\r\nN8 G4 X0.2\r\n");
    let (c, ev, v) = run_stream(&s, &[(1, &text), (3000, "N9 M30\r\n")], 6000);
    let b = blocks(&ev);
    let t6 = b.iter().find(|x| x.1 == Some(6)).unwrap().0 as usize;
    let t7 = b.iter().find(|x| x.1 == Some(7)).unwrap().0 as usize;
    let t8 = b.iter().find(|x| x.1 == Some(8)).unwrap().0 as usize;
    // M5 when interpolation reaches it: the axes have just stopped at X30, long before M30.
    assert!(t7 > t6 && t7 < 2000, "M5 at tick {t7}");
    assert!(
        v[t7] == 0.0 && v[t7 - 1] > 0.0,
        "M5 in the tick the motion ends: {:?}",
        &v[t7 - 3..t7 + 2]
    );
    assert!(t8 >= t7 && t8 < 2000, "G4 at tick {t8}");
    // Waiting for M30 after the dwell is an interrupt with nothing held.
    let held: Vec<(u64, u64)> = ev
        .iter()
        .filter_map(|e| match e.1 {
            EventKind::Interrupt { held } => Some((e.0, held)),
            _ => None,
        })
        .collect();
    assert_eq!(held.len(), 1, "{held:?}");
    assert_eq!(held[0].1, 0);
    assert!(
        held[0].0 as usize > t8 + 150,
        "not during the dwell: {held:?}"
    );
    assert_eq!(c.report().position[0], 30.0);
}

/// Run a program file to its end; every tick's position and path velocity.
fn run_file(s: &Setup, name: &str, text: &str, max_ticks: u64) -> (Vec<[f64; 6]>, Vec<f64>) {
    s.write(&format!("nc/{name}"), text);
    let mut c = s.channel();
    start(&mut c, &tick(0), name);
    let (mut pos, mut vel) = (Vec::new(), Vec::new());
    for k in 1..max_ticks {
        c.step(&tick(k));
        pos.push(c.report().position);
        vel.push(c.status().velocity_mm_per_s);
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    (pos, vel)
}

/// Distance of (x, y) from the closed polygon through `corners`.
fn distance_to_polygon(x: f64, y: f64, corners: &[(f64, f64)]) -> f64 {
    (0..corners.len())
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let t = (((x - a.0) * dx + (y - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (x - a.0 - t * dx).hypot(y - a.1 - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The lowest path velocity between leaving the start and arriving at the end (50 ticks of
/// acceleration and braking left out).
fn slowest_while_moving(vel: &[f64]) -> f64 {
    let first = vel.iter().position(|v| *v > 0.0).unwrap();
    let last = vel.iter().rposition(|v| *v > 0.0).unwrap();
    vel[first + 50..last - 50]
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn contoured_square_stays_within_the_deviation_and_does_not_stop_at_corners() {
    // With the shipped planner, and with the corner filter CAM polylines want: a contoured
    // run does without it, so its blends stay exact.
    for planner in [
        "",
        "[planner]\nlookahead_blocks = 128\ncorner_smoothing_ms = 50\n",
    ] {
        contoured_square(&Setup::new("", planner));
    }
    let s = Setup::new("", "");
    // Without G261 the same square stops at each corner.
    let sharp = "G1 X50 F3000\nY50\nX0\nY0\nM30\n";
    let (_, vel) = run_file(&s, "sharp.nc", sharp, 20_000);
    let slowest = slowest_while_moving(&vel);
    assert!(slowest < 1.0, "{slowest}");
}

#[test]
fn a_flush_while_contouring_keeps_its_corner_sharp_and_the_others_blended() {
    // Kernels since V2.10.1503.08 accept #FLUSH with polynomial contouring on and suppress
    // the blend at the motion blocks around it (TF5200 "Flushing NC channel").
    for flush in ["#FLUSH WAIT", "#FLUSH", "#FLUSH CONTINUE"] {
        let s = Setup::new("", "");
        let program = format!("G261\nG1 X50 F3000\nY50\n{flush}\nX0\nY0\nG260\nM30\n");
        let (pos, _) = run_file(&s, "flush.nc", &program, 20_000);
        let closest = |cx: f64, cy: f64| {
            pos.iter()
                .map(|p| (p[0] - cx).hypot(p[1] - cy))
                .fold(f64::INFINITY, f64::min)
        };
        // The corner at the flush (50, 50) stays sharp (passed at the speed of a sharp corner,
        // sampled within 1 µm); (50, 0) and (0, 50) are blended.
        assert!(closest(50.0, 50.0) < 1e-3, "{flush}");
        assert!(closest(50.0, 0.0) > 0.04, "{flush}");
        assert!(closest(0.0, 50.0) > 0.04, "{flush}");
    }
}

fn contoured_square(s: &Setup) {
    let program = "#CONTOUR MODE [DEV PATH_DEV=0.05]\nG261\nG1 X50 F3000\nY50\nX0\nY0\n\
                   G260\nM30\n";
    let (pos, vel) = run_file(s, "square.nc", program, 20_000);
    let square = [(0.0, 0.0), (50.0, 0.0), (50.0, 50.0), (0.0, 50.0)];
    let worst = pos
        .iter()
        .map(|p| distance_to_polygon(p[0], p[1], &square))
        .fold(0.0, f64::max);
    assert!(worst <= 0.05 + 1e-9, "deviation {worst} mm");
    // The blend passes the corner point at the permitted deviation (the distance to the
    // polygon's edges is that times cos 45°).
    let closest = pos
        .iter()
        .map(|p| (p[0] - 50.0).hypot(p[1] - 50.0))
        .fold(f64::INFINITY, f64::min);
    assert!((0.0499..=0.0501).contains(&closest), "{closest} mm");
    assert!(worst > 0.03, "the corners are blended ({worst} mm)");
    // From leaving the start until arriving back: never standing.
    let slowest = slowest_while_moving(&vel);
    assert!(slowest > 5.0, "slowed to {slowest} mm/s");
    assert_eq!(pos.last().map(|p| (p[0], p[1])), Some((0.0, 0.0)));
}

#[test]
fn run_trace_writes_a_header_and_one_row_per_stride_ending_at_the_end_point() {
    let s = Setup::new(
        "",
        "[[axes]]\nname = \"X\"\nmax_jerk_mm_per_s3 = 20000.0\n\
         [[axes]]\nname = \"Y\"\nmax_jerk_mm_per_s3 = 20000.0\n",
    );
    let stream = s.write("nc/sq.nc", "G1 X20 F3000\nY20\nM30\n");
    let csv = s.dir.path().join("trace.csv");
    let r = run_report(
        &s,
        &stream,
        &["--trace", csv.to_str().unwrap(), "--trace-every", "5"],
    );
    let ticks = r["ticks"].as_u64().unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,X_mm,Y_mm,velocity_mm_per_s,acceleration_mm_per_s2,jerk_mm_per_s3")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(
        rows.len() as u64,
        ticks.div_ceil(5),
        "one row every 5 ticks"
    );
    assert!(rows
        .windows(2)
        .all(|w| (w[1][0] - w[0][0] - 0.005).abs() < 1e-9));
    let peak_jerk = rows.iter().map(|r| r[5].abs()).fold(0.0, f64::max);
    assert!(peak_jerk > 1000.0, "jerk is traced ({peak_jerk})");
    let last = rows.last().unwrap();
    assert_eq!((last[1], last[2]), (20.0, 20.0));
    // The filter's last step into the end point may be a rounding residue (nm per tick).
    assert!(last[3].abs() < 1e-3, "{}", last[3]);
}

/// The seed's streaming-spline example (nc/streaming_spline.nc), with the feed the excerpt
/// leaves out.
/// Lines end in CR LF, as the stream interface wants them.
fn streaming_spline_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("nc/streaming_spline.nc"))
        .unwrap()
        .lines()
        .map(|l| format!("{l}\r\n"))
        .collect()
}

/// The example is a B-spline (`#SPLINE TYPE BSPLINE`, G151): the motion follows the curve
/// through the streamed points without stopping at them.
#[test]
fn streaming_spline_example_in_packets_passes_its_points_without_stopping() {
    let s = Setup::new("", "");
    let text = streaming_spline_text();
    // Packets of two lines, one every 5 ticks: the example arrives while it runs.
    let lines: Vec<&str> = text.split_inclusive("\r\n").collect();
    let writes: Vec<(u64, String)> = lines
        .chunks(2)
        .enumerate()
        .map(|(i, c)| (1 + 5 * i as u64, c.concat()))
        .collect();
    let refs: Vec<(u64, &str)> = writes.iter().map(|(t, w)| (*t, w.as_str())).collect();
    let (c, ev, v) = run_stream(&s, &refs, 20_000);
    assert!(c.report().errors.is_empty(), "{:?}", c.report().errors);
    let b = blocks(&ev);
    let first = b.iter().find(|x| x.1 == Some(36338)).unwrap().0 as usize;
    let last = b.iter().find(|x| x.1 == Some(36355)).unwrap().0 as usize;
    let slowest = v[first..last].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        slowest > 1.0,
        "stopped at a programmed point: {slowest} mm/s"
    );
    assert!((c.report().position[2] - 1.8353).abs() < 1e-9);
}

#[test]
fn flush_inside_the_streaming_spline_is_120102() {
    let s = Setup::new("", "");
    let text = streaming_spline_text().replace("N36345", "#FLUSH\r\nN36345");
    let (head, tail) = text.split_at(text.find("N36340").unwrap());
    let (c, _, _) = run_stream(&s, &[(1, head), (2, tail)], 20_000);
    assert_eq!(
        c.report().last_error.map(|e| e.code),
        Some(120102),
        "{:?}",
        c.report().errors
    );
}

/// Distance of (x, y) from the circle of radius `r` around (cx, cy).
fn distance_to_circle(x: f64, y: f64, cx: f64, cy: f64, r: f64) -> f64 {
    ((x - cx).hypot(y - cy) - r).abs()
}

/// Positions of a program run with the tool list D1 = 5 mm, between the first and the last
/// block whose `N` lies in `from..=to` (the compensated contour without selection and
/// deselection).
fn trc_run(program: &str, from: u64, to: u64) -> Vec<[f64; 6]> {
    let s = Setup::new("", "");
    s.write("params/tools.lis", "wz[1].radius 50000\n");
    positions_between(&s, program, from, to)
}

/// Positions of `program` run in the set-up `s`, between the first and the last block whose
/// `N` lies in `from..=to`; the run must end without error.
fn positions_between(s: &Setup, program: &str, from: u64, to: u64) -> Vec<[f64; 6]> {
    s.write("nc/trc.nc", program);
    let mut c = s.channel();
    start(&mut c, &tick(0), "trc.nc");
    let (mut inside, mut out) = (false, Vec::new());
    for k in 1..200_000u64 {
        c.step(&tick(k));
        for e in c.events_mut().events() {
            if let EventKind::Block { n: Some(n), .. } = e.kind {
                inside = (from..=to).contains(&n);
            }
        }
        c.events_mut().flush_to(&mut EventLog::disabled());
        if inside {
            out.push(c.report().position);
        }
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    out
}

#[test]
fn trc_square_and_circle_stay_equidistant_to_the_programmed_path() {
    let square = [(0.0, 0.0), (50.0, 0.0), (50.0, 50.0), (0.0, 50.0)];
    for (g, outside) in [("G41", false), ("G42", true)] {
        // A counter-clockwise square: G41 keeps the tool inside (corners cut at the
        // intersections), G42 outside (arcs around the corners).
        let program = format!(
            "G0 X-20 Y-20\nN1 {g} D1 G1 X0 Y0 F3000\nN2 X50\nN3 Y50\nN4 X0\nN5 Y0\nN6 X10\n\
             N7 G40 X-20 Y-20\nM30\n"
        );
        let pos = trc_run(&program, 3, 5);
        assert!(pos.len() > 1000);
        let worst = pos
            .iter()
            .map(|p| (distance_to_polygon(p[0], p[1], &square) - 5.0).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-3 * 1.0, "{g}: off by {worst} mm");
        // Outside the square for G42, inside for G41.
        let mid = pos[pos.len() / 2];
        let inside = (0.0..=50.0).contains(&mid[0]) && (0.0..=50.0).contains(&mid[1]);
        assert_eq!(inside, !outside, "{g}: {mid:?}");
    }
    for (g, r) in [("G41", 25.0), ("G42", 35.0)] {
        // A counter-clockwise full circle of radius 30 around (0, 0), entered from the left.
        let program = format!(
            "G0 X-60 Y0\nN1 {g} D1 G1 X-30 Y0 F3000\nN2 G3 X-30 Y0 I30 J0\nN3 G2 X-20 Y-10 R10\n\
             N4 G40 G1 X-60 Y-40\nM30\n"
        );
        let pos = trc_run(&program, 2, 2);
        assert!(pos.len() > 500);
        // The arc around the circle's end point (G42: an outer corner towards N3) is
        // equidistant to that point, not to the circle: left out.
        let worst = pos
            .iter()
            .filter(|p| (p[0] + 30.0).hypot(p[1]) > 5.0 + 1e-6)
            .map(|p| distance_to_circle(p[0], p[1], 0.0, 0.0, r))
            .fold(0.0, f64::max);
        assert!(worst <= 1e-3, "{g}: off by {worst} mm");
    }
}

#[test]
fn trc_radius_larger_than_an_inner_arc_is_error_900140() {
    let s = Setup::new("", "");
    s.write("params/tools.lis", "wz[1].radius 50000\n");
    let program = "G0 X-10 Y0\nG41 D1 G1 X0 Y0 F3000\nG3 X6 Y0 I3 J0\nG1 X20\nG40 X30\nM30\n";
    s.write("nc/bad_trc.nc", program);
    let mut c = s.channel();
    start(&mut c, &tick(0), "bad_trc.nc");
    for k in 1..20_000u64 {
        c.step(&tick(k));
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Error);
    assert_eq!(
        c.report().last_error.map(|e| e.code),
        Some(900140),
        "{:?}",
        c.report().errors
    );
}

/// Run `program` to its end or its first error: the channel's errors and the largest |X|
/// the axes reached.
fn run_to_error(runtime: &str, program: &str) -> (Vec<ncchannel::channel::ErrorRecord>, f64) {
    let s = Setup::new("", runtime);
    s.write("params/tools.lis", "wz[1].radius 50000\n");
    s.write("nc/lim.nc", program);
    let mut c = s.channel();
    start(&mut c, &tick(0), "lim.nc");
    let mut x_max: f64 = 0.0;
    for k in 1..200_000u64 {
        c.step(&tick(k));
        x_max = x_max.max(c.report().position[0].abs());
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active {
            break;
        }
    }
    (c.report().errors.to_vec(), x_max)
}

#[test]
fn a_compensated_path_beyond_a_software_limit_is_21897_before_the_axis_gets_there() {
    // Soft limit X ≤ 1000 (the default) and a 5 mm tool: the programmed points lie on the
    // limit, the compensated outer corner around (1000, 0) would take X to 1005.
    let program = "N1 G17 G41 D1 G01 X0 Y0 F1000\nN2 G01 X1000 Y0\nN3 G01 X1000 Y-100\n\
                   N4 G40 G01 X900 Y-100\nM30\n";
    let (errors, x_max) = run_to_error("", program);
    assert_eq!(errors.len(), 1, "{errors:?}");
    let e = &errors[0];
    assert_eq!(e.code, 21897, "{e:?}");
    assert!(
        e.msg.contains("axis X compensated path reaches 1005"),
        "{}",
        e.msg
    );
    assert_eq!(
        (e.prog.as_deref(), e.line),
        (Some("lim.nc"), Some(2)),
        "{e:?}"
    );
    assert!(x_max <= 1000.0, "the axis reached {x_max}");
    // The same contour with the limit out of reach runs to its end.
    let wide = "[[axes]]\nname = \"X\"\nsoft_limit_max_mm = 1010.0\n[[axes]]\nname = \"Y\"\n";
    let (errors, x_max) = run_to_error(wide, program);
    assert!(errors.is_empty(), "{errors:?}");
    assert!((x_max - 1005.0).abs() < 1e-6, "{x_max}");
}

#[test]
fn an_axis_outside_its_limits_may_move_back_inside_but_not_further_out() {
    // X starts at 0, below its lower limit 10.
    let rt = "[[axes]]\nname = \"X\"\nsoft_limit_min_mm = 10.0\n[[axes]]\nname = \"Y\"\n";
    let (errors, x_max) = run_to_error(rt, "G1 X20 F3000\nM30\n");
    assert!(errors.is_empty(), "{errors:?}");
    assert_eq!(x_max, 20.0);
    let (errors, _) = run_to_error(rt, "G1 X-5 F3000\nM30\n");
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!(errors[0].code, 21897);
    // The message names the end point that lies further out, not the start.
    assert!(
        errors[0]
            .msg
            .contains("axis X end point -5 mm, below the lower"),
        "{}",
        errors[0].msg
    );
}

#[test]
fn a_negative_dwell_is_refused_with_the_kernels_range_error() {
    for (program, code) in [("G04 X-1\nM30\n", 20752), ("#TIME -0.5\nM30\n", 20751)] {
        let (errors, _) = run_to_error("", program);
        assert_eq!(errors.len(), 1, "{program}: {errors:?}");
        assert_eq!(errors[0].code, code, "{program}: {errors:?}");
        assert!(errors[0].msg.contains("µs"), "{}", errors[0].msg);
    }
    // Zero is a dwell of no time.
    let (errors, _) = run_to_error("", "G04 X0\nM30\n");
    assert!(errors.is_empty(), "{errors:?}");
}

/// A set-up in the kernel's format: the start-up list names the tool list (`werkz_data[0]`,
/// P-STUP-00010) and the zero-offset list (`nullp_data[0]`, P-STUP-00011); the channel list
/// gets `channel_extra`.
fn kernel_lists(channel_extra: &str) -> Setup {
    let s = Setup::new("werkz_data[0] werkz_d.lis\nnullp_data[0] nullp_d.lis\n", "");
    s.write(
        "params/channel1.lis",
        &format!("streaming_prog_file streaming.nc\n{channel_extra}"),
    );
    // A tools.lis next to the start-up list is not read when werkz_data names a list.
    s.write("params/tools.lis", "wz[1].radius 90000\n");
    s.write(
        "params/werkz_d.lis",
        "# TF5200 Tool data, 0.1 um\n\
         wz[1].gueltig 1\nwz[1].radius 30000\nwz[1].laenge 0\n\
         wz[2].gueltig 1\nwz[2].radius 20000\nwz[2].laenge 600000\nwz[2].ax_versatz[0] 15000\n\
         wz[3].radius 10000\n",
    );
    s.write(
        "params/nullp_d.lis",
        "# TF5200 Zero offset group: 0 = G53, 1 = G54 ... 6 = G59\n\
         np_grp[0].achse[0].versch 70000\n\
         np_grp[1].achse[0].versch 100000\n\
         np_grp[2].achse[1].versch -30000\n\
         np_grp[6].achse[2].versch 25000\n",
    );
    s
}

/// Run `program` to its end (or first error); the channel after it.
fn run_program(s: &Setup, program: &str) -> Channel {
    s.write("nc/tool.nc", program);
    let mut c = s.channel();
    start(&mut c, &tick(0), "tool.nc");
    for k in 1..200_000u64 {
        c.step(&tick(k));
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active {
            break;
        }
    }
    c
}

fn ended_at(s: &Setup, program: &str) -> [f64; 6] {
    let c = run_program(s, program);
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    c.report().position
}

#[test]
fn g41_d1_offsets_the_path_by_the_radius_of_the_werkz_data_list() {
    let s = kernel_lists("");
    let square = [(0.0, 0.0), (50.0, 0.0), (50.0, 50.0), (0.0, 50.0)];
    let program = "G0 X-20 Y-20\nN1 G41 D1 G1 X0 Y0 F3000\nN2 X50\nN3 Y50\nN4 X0\nN5 Y0\n\
                   N6 X10\nN7 G40 X-20 Y-20\nM30\n";
    let pos = positions_between(&s, program, 3, 5);
    assert!(pos.len() > 1000);
    for p in &pos {
        let d = distance_to_polygon(p[0], p[1], &square);
        assert!(
            (d - 3.0).abs() <= 1e-3,
            "{p:?}: {d} mm from the contour, not 3"
        );
    }
}

#[test]
fn tool_length_lies_on_the_tool_axis_and_axis_offsets_on_their_axes() {
    let s = kernel_lists("");
    // G17: the length (60 mm) on Z; ax_versatz[0] (1.5 mm) on X.
    let p = ended_at(&s, "G17 G90 D2 G0 X0 Y0 Z0\nM30\n");
    assert_eq!((p[0], p[1], p[2]), (1.5, 0.0, 60.0));
    // G18: on Y.
    let p = ended_at(&s, "G18 G90 D2 G0 X0 Y0 Z0\nM30\n");
    assert_eq!((p[0], p[1], p[2]), (1.5, 60.0, 0.0));
    // A new D takes effect at the axis' next absolute position (P-CHAN-00100 default);
    // D0 takes it off.
    let p = ended_at(&s, "G90 G0 Z0\nD2\nG91 Z0\nG90 X0\nM30\n");
    assert_eq!((p[0], p[2]), (1.5, 0.0));
    let p = ended_at(&s, "G90 D2 G0 Z0\nD0 Z10\nM30\n");
    assert_eq!(p[2], 10.0);
}

#[test]
fn an_invalid_tool_is_refused_with_its_error_where_d_selects_it() {
    let s = kernel_lists("");
    // wz[3] has no `gueltig 1`: the kernel's default 0, invalid.
    let c = run_program(&s, "G0 X0 Y0\nG1 X1 D3 F1000\nG41 G1 X10\nG40 X20\nM30\n");
    assert_eq!(c.status().state, State::Error);
    let e = c.report().last_error.unwrap();
    assert_eq!((e.code, e.line), (900140, Some(2)), "{}", e.msg);
    assert!(e.msg.contains("gueltig"), "{}", e.msg);
    assert!(e.msg.contains("(column 7)"), "at the D word: {}", e.msg);
    assert_eq!(c.report().position[0], 0.0, "the block does not move");
    // With einrechnen_mit_t the T word selects it, and is the place named.
    let c = run_program(&kernel_lists("einrechnen_mit_t 1\n"), "N1 T3 M6\nM30\n");
    let e = c.report().last_error.unwrap();
    assert_eq!(e.code, 900140);
    assert!(e.msg.contains("(column 4)"), "at the T word: {}", e.msg);
}

#[test]
fn g54_to_g59_take_the_kernel_numbered_groups_of_nullp_data() {
    let s = kernel_lists("");
    // np_grp[0] (G53) is not G54: G54 is np_grp[1].
    let p = ended_at(&s, "G54 G90 G01 X0 F3000\nM30\n");
    assert_eq!(p[0], 10.0);
    let p = ended_at(&s, "G55 G90 G0 X0 Y0\nM30\n");
    assert_eq!((p[0], p[1]), (0.0, -3.0));
    let p = ended_at(&s, "G59 G90 G0 Z0\nG53 G0 X0\nM30\n");
    assert_eq!((p[0], p[2]), (0.0, 2.5));
}

#[test]
fn v_g_wz_akt_and_v_g_np_read_the_lists() {
    let s = kernel_lists("");
    // Each value is read into an axis position under G53 (no offset) and D0.
    let p = ended_at(
        &s,
        "D2\nP1 = V.G.WZ_AKT.R\nP2 = V.G.WZ_AKT.L\nP3 = V.G.WZ_AKT.OK + V.G.WZ[3].OK\n\
         P4 = V.G.WZ_AKT.V.X + V.G.WZ[2].V[1]\nD0\nG53 G90 G0 X[P1] Y[P2] Z[P3 + P4]\nM30\n",
    );
    assert_eq!((p[0], p[1], p[2]), (2.0, 60.0, 2.5));
    let p = ended_at(
        &s,
        "G53 G90 G0 X[V.G.NP[1].V.X] Y[V.G.NP[2].V[1]] Z[V.G.NP[6].V.Z + V.G.NP[0].V.X]\nM30\n",
    );
    assert_eq!((p[0], p[1], p[2]), (10.0, -3.0, 2.5));
}

#[test]
fn a_program_writes_zero_offsets_through_v_g_np_and_they_outlive_a_reset() {
    let s = kernel_lists("");
    // TF5200 "Zero offsets": `V.G.NP[1].V.X=10` then `G54` (group 1).
    let mut c = run_program(
        &s,
        "V.G.NP[1].V.X = 25\nV.G.NP[2].V[1] = -4\nG54 G90 G0 X0\nM30\n",
    );
    assert_eq!(c.report().position[0], 25.0);
    // The table is the channel's data: the next program, after a reset, still sees it.
    c.apply(&tick(200_000), Op::Reset);
    s.write(
        "nc/next.nc",
        "G55 G90 G0 X0 Y0\nP1 = V.G.NP[1].V.X\nG53 G0 Z[P1]\nM30\n",
    );
    start(&mut c, &tick(200_001), "next.nc");
    for k in 200_002..400_000u64 {
        c.step(&tick(k));
        c.events_mut().flush_to(&mut EventLog::disabled());
        if c.status().state != State::Active {
            break;
        }
    }
    assert_eq!(c.status().state, State::Ready, "{:?}", c.report().errors);
    let p = c.report().position;
    assert_eq!((p[1], p[2]), (-4.0, 25.0));
    // Group 0 is G53 (no offset) and cannot be written; nor can tool data.
    for prog in ["V.G.NP[0].V.X = 1\nM30\n", "V.G.WZ_AKT.L = 5\nM30\n"] {
        let c = run_program(&s, prog);
        assert_eq!(
            c.report().last_error.map(|e| e.code),
            Some(900133),
            "{prog}"
        );
    }
}

#[test]
fn einrechnen_mit_t_makes_t_select_the_d_data_set_of_its_number() {
    let p = ended_at(
        &kernel_lists("einrechnen_mit_t 1\n"),
        "T2\nG90 G0 Z0\nM30\n",
    );
    assert_eq!(p[2], 60.0, "T2 is T2 D2");
    let p = ended_at(&kernel_lists(""), "T2\nG90 G0 Z0\nM30\n");
    assert_eq!(p[2], 0.0, "without it T selects no data");
}

#[test]
fn bad_tool_and_zero_offset_entries_are_refused_with_file_line_and_column() {
    let s = kernel_lists("");
    s.write("params/werkz_d.lis", "wz[1].radius 1\nwz[1].gueltig 2\n");
    s.write("params/nullp_d.lis", "np_grp[1].achse[0].versch 1.5\n");
    let e = ncchannel::params::load(&s.startup()).unwrap_err();
    let at: Vec<(String, usize, usize)> = e
        .errors()
        .iter()
        .filter(|d| d.severity == ncchannel::Severity::Error)
        .map(|d| {
            let f = d.file.file_name().unwrap().to_string_lossy().into_owned();
            (f, d.line, d.col)
        })
        .collect();
    assert_eq!(
        at,
        [("nullp_d.lis".into(), 1, 27), ("werkz_d.lis".into(), 2, 15)]
    );
    // Each list checks on its own as well (`ncchannel check`).
    let d = ncchannel::params::check_list_file(&s.dir.path().join("params/werkz_d.lis"));
    assert_eq!((d.len(), d[0].line, d[0].col), (1, 2, 15), "{d:?}");
}
