//! A TwinCAT CNC installation's own lists start the channel: an installation folder
//! (`listen/`, `prg/`, `error/`) in the kernel's list format, axes from the axis lists
//! (TF5200 Axis parameter P-AXIS-00008/-00177/-00178/-00209/-00212), the implicitly called
//! subroutines of the channel list (P-CHAN-00119, -00252, -00118), the streaming program
//! name (P-CHAN-00158) and the error text file (P-STUP-00168).

use std::path::{Path, PathBuf};
use std::time::Duration;

use ncchannel::channel::{Channel, State};
use ncchannel::machine::{Op, Reply};
use ncchannel::report::event::{EventKind, EventLog};
use ncchannel::runtime::Tick;

use crate::support::{start, write, WRITTEN};

const PERIOD: Duration = Duration::from_millis(1);

/// An installation in a temp folder: `listen/hochlauf.lis`, `listen/sda_mds1.lis`,
/// `listen/achsmds1..3.lis` over `listen/default_mds.lis`, `error/err_text_version_eng.txt`,
/// programs in `prg/`. Lists are written in Latin-1 with the kernel's constructs.
struct Installation {
    dir: tempfile::TempDir,
}

/// X: 100 mm/s (6000 mm/min), rapid 50 mm/s, 500 mm/s², limits ±1500 mm; ramp times 0 (no
/// jerk limit), so a move's time is the trapezoid's.
const DEFAULT_MDS: &str = "# Standard-Achsparameter (Umlaute: \u{e4}\u{f6}\u{fc})\n\
    kenngr.achs_typ ACHSTYP_TRANSLATOR ( P-AXIS-00018\n\
    getriebe[0].dynamik.vb_max 100000 ( P-AXIS-00212 : [um/s]\n\
    getriebe[0].vb_eilgang 50000 ( P-AXIS-00209 : [um/s]\n\
    getriebe[0].dynamik.a_max 500 ( P-AXIS-00008 : [mm/s^2]\n\
    getriebe[0].slope_profil.a_brems P-AXIS-00008.0\n\
    getriebe[0].slope_profil.tr_beschl_zu 0\n\
    getriebe[0].slope_profil.tr_beschl_ab 0\n\
    getriebe[0].slope_profil.tr_brems_zu 0\n\
    getriebe[0].slope_profil.tr_brems_ab 0\n\
    getriebe[0].dynamik.tr_min 0\n\
    #lr_param.kv_faktor 1000\n\
    Ende\n";

const CHANNEL: &str = "gruppe[0].bezeichnung GRUPPE_1 ( P-CHAN-00005\n\
    gruppe[0].achse[0].bezeichnung X\ngruppe[0].achse[0].log_achs_nr 1\n\
    gruppe[0].achse[1].bezeichnung Y\ngruppe[0].achse[1].log_achs_nr 2\n\
    gruppe[0].achse[2].bezeichnung Z\ngruppe[0].achse[2].log_achs_nr 3\n\
    #spindel[0].range_way 0\n\
    streaming_prog_file streaming.nc ( P-CHAN-00158\n\
    configuration.interpolator.function FCT_DEFAULT | FCT_SURFACE\n";

impl Installation {
    /// `channel_extra` is appended to the channel list.
    fn new(channel_extra: &str) -> Installation {
        let dir = tempfile::tempdir().unwrap();
        let i = Installation { dir };
        i.latin1(
            "listen/hochlauf.lis",
            "kanal_anzahl 1 ( P-STUP-00001 : Anzahl Kan\u{e4}le\n\
             default_achs_mds ./listen/default_mds.lis\n\
             achs_mds[0] ./listen/achsmds1.lis\nachs_mds[1] ./listen/achsmds2.lis\n\
             achs_mds[2] ./listen/achsmds3.lis\n\
             sda_mds[0] ./listen/sda_mds1.lis ( Kanal 1\n\
             pfad[0].prg[0] ./prg\npfad[0].typ[0] 0x03\npfad[0].prioritaet[0] 0\n\
             error_text_of_id ./error/err_text_version_eng.txt\nEnde\n",
        );
        i.latin1("listen/default_mds.lis", DEFAULT_MDS);
        for (nr, name) in [(1, "X"), (2, "Y"), (3, "Z")] {
            i.latin1(
                &format!("listen/achsmds{nr}.lis"),
                &format!(
                    "kopf.achs_nr {nr}\nkopf.log_achs_name {name}\n\
                     kenngr.swe_pos 15000000 ( P-AXIS-00178 : [0.1um] Positive software limit switch\n\
                     kenngr.swe_neg -15000000 ( P-AXIS-00177\nEnde\n"
                ),
            );
        }
        i.latin1(
            "listen/sda_mds1.lis",
            &format!("{CHANNEL}{channel_extra}Ende\n"),
        );
        i.write(
            "error/err_text_version_eng.txt",
            "21897\tAxis position is out of permissible range.\n",
        );
        i
    }

    fn latin1(&self, rel: &str, text: &str) {
        let bytes: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
        self.write_bytes(rel, &bytes);
    }

    fn write(&self, rel: &str, text: &str) {
        self.write_bytes(rel, text.as_bytes());
    }

    fn write_bytes(&self, rel: &str, bytes: &[u8]) {
        let p = self.dir.path().join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }

    fn startup(&self) -> PathBuf {
        self.dir.path().join("listen/hochlauf.lis")
    }

    fn channel(&self) -> Channel {
        let config = ncchannel::params::load(&self.startup()).unwrap_or_else(|e| panic!("{e}"));
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

/// Step the channel until it is neither active nor held; `writes` go into the stream at
/// their tick. Every event with its tick.
fn run(c: &mut Channel, writes: &[(u64, &str)], max_ticks: u64) -> Vec<(u64, EventKind)> {
    let mut events = Vec::new();
    for k in 1..max_ticks {
        let t = tick(k);
        for (at, text) in writes {
            if *at == k {
                assert_eq!(write(c, &t, text.as_bytes()), WRITTEN);
            }
        }
        c.step(&t);
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
    events
}

/// The programs of the block events, in order, with their block numbers.
fn blocks(events: &[(u64, EventKind)]) -> Vec<(String, Option<u64>)> {
    events
        .iter()
        .filter_map(|(_, e)| match e {
            EventKind::Block { prog, n, .. } => Some((prog.clone(), *n)),
            _ => None,
        })
        .collect()
}

/// [`blocks`] with a missing block number as 0, to compare with a literal list.
fn numbered_blocks(events: &[(u64, EventKind)]) -> Vec<(String, u64)> {
    blocks(events)
        .into_iter()
        .map(|(p, n)| (p, n.unwrap_or(0)))
        .collect()
}

fn end_tick(events: &[(u64, EventKind)]) -> u64 {
    events
        .iter()
        .find(|(_, e)| matches!(e, EventKind::ProgramEnd { .. }))
        .map(|(t, _)| *t)
        .unwrap_or_else(|| panic!("no program end: {events:#?}"))
}

/// Time of a rest-to-rest move of `d` mm at most `v` mm/s with acceleration `a` mm/s² and no
/// jerk limit: d/v + v/a when `v` is reached, else 2·√(d/a).
fn trapezoid_s(d: f64, v: f64, a: f64) -> f64 {
    if d >= v * v / a {
        d / v + v / a
    } else {
        2.0 * (d / a).sqrt()
    }
}

#[test]
fn a_move_runs_at_the_axis_lists_velocity_and_acceleration() {
    let i = Installation::new("");
    // F20000 asks more than vb_max (100000 µm/s = 6000 mm/min): the axis list limits it.
    i.write("prg/feed.nc", "N10 G01 X200 F20000\nN20 M30\n");
    i.write("prg/rapid.nc", "N10 G00 X200\nN20 M30\n");
    for (prog, v) in [("feed.nc", 100.0), ("rapid.nc", 50.0)] {
        let mut c = i.channel();
        start(&mut c, &tick(0), prog);
        let ev = run(&mut c, &[], 20_000);
        let measured = end_tick(&ev) as f64 * PERIOD.as_secs_f64();
        let analytic = trapezoid_s(200.0, v, 500.0);
        assert!(
            (measured - analytic).abs() <= 0.01 * analytic,
            "{prog}: {measured} s against the analytic {analytic} s"
        );
        assert_eq!(c.report().position[0], 200.0);
    }
}

#[test]
fn beyond_swe_pos_is_refused_with_21897_and_the_kernels_text() {
    let i = Installation::new("");
    // swe_pos 15000000 × 0.1 µm = 1500 mm.
    i.write("prg/edge.nc", "N10 G01 X1500 F6000\nN20 M30\n");
    i.write("prg/far.nc", "N10 G01 X1500.001 F6000\nN20 M30\n");
    let mut c = i.channel();
    start(&mut c, &tick(0), "edge.nc");
    let ev = run(&mut c, &[], 40_000);
    assert!(!ev.iter().any(|(_, e)| matches!(e, EventKind::Error { .. })));
    assert_eq!(c.report().position[0], 1500.0);

    let mut c = i.channel();
    start(&mut c, &tick(0), "far.nc");
    let ev = run(&mut c, &[], 1000);
    let (code, msg) = ev
        .iter()
        .find_map(|(_, e)| match e {
            EventKind::Error { code, msg, .. } => Some((*code, msg.clone())),
            _ => None,
        })
        .expect("an error");
    assert_eq!(code, 21897);
    // The kernel's text once, then ncchannel's detail once in parentheses: in the event,
    // the channel's last-error record and its list of errors (the run report's).
    assert_eq!(
        msg,
        "Axis position is out of permissible range. (axis X end point 1500.001 mm, \
         above the upper software limit (limits -1500 to 1500 mm))"
    );
    let report = c.report();
    let last = report.last_error.as_ref().expect("a last error");
    assert_eq!((last.code, last.msg.as_str()), (21897, msg.as_str()));
    assert_eq!(report.errors.len(), 1);
    assert_eq!(report.errors[0].msg, msg);
    assert_eq!(report.position[0], 0.0, "nothing moved");
}

const IMPLICIT: &str = "start_init_prog_file init.nc ( P-CHAN-00119\n\
    final_prog_file final.nc ( P-CHAN-00252\n\
    m6_prog_file tool.nc ( P-CHAN-00118\n";

fn implicit_programs(i: &Installation) {
    i.write("prg/init.nc", "N1 G90\nN2 G01 X1 F6000\nN3 M17\n");
    i.write("prg/final.nc", "N7 G01 X3 F6000\nN8 M17\n");
    // An M6 in the tool change program is an ordinary M function, not a second call.
    i.write("prg/tool.nc", "N4 G01 Z5 F6000\nN5 M6\nN6 M17\n");
}

#[test]
fn implicit_subroutines_run_at_program_start_m6_and_program_end() {
    let i = Installation::new(IMPLICIT);
    implicit_programs(&i);
    i.write(
        "prg/part.nc",
        "N10 G01 X2 F6000\nN20 T1 M6\nN30 G01 Y2\nN40 M30\n",
    );
    let mut c = i.channel();
    start(&mut c, &tick(0), "part.nc");
    let ev = run(&mut c, &[], 20_000);
    let b = blocks(&ev);
    let got: Vec<(&str, u64)> = b
        .iter()
        .map(|(p, n)| (p.as_str(), n.unwrap_or(0)))
        .collect();
    assert_eq!(
        got,
        vec![
            ("init.nc", 1),
            ("init.nc", 2),
            ("init.nc", 3),
            ("part.nc", 10),
            ("part.nc", 20),
            ("tool.nc", 4),
            ("tool.nc", 5),
            ("tool.nc", 6),
            ("part.nc", 30),
            ("part.nc", 40),
            ("final.nc", 7),
            ("final.nc", 8),
        ]
    );
    // The end comes after the end subroutine ran: X at 3 (final.nc), Z at 5 (tool.nc).
    let end = end_tick(&ev);
    assert!(
        ev.iter()
            .filter(|(_, e)| matches!(e, EventKind::Block { .. }))
            .all(|(t, _)| *t <= end),
        "{ev:#?}"
    );
    let p = c.report().position;
    assert_eq!((p[0], p[1], p[2]), (3.0, 2.0, 5.0));
    assert!(ev.iter().any(|(_, e)| *e
        == EventKind::ProgramEnd {
            prog: "part.nc".into(),
            end: ncchannel::report::event::ProgramEndKind::M30
        }));
}

#[test]
fn implicit_subroutines_run_in_a_stream_started_under_the_channel_lists_name() {
    let i = Installation::new(IMPLICIT);
    implicit_programs(&i);
    let mut c = i.channel();
    // `streaming.nc` is the channel list's streaming_prog_file (P-CHAN-00158).
    start(&mut c, &tick(0), "streaming.nc");
    let ev = run(
        &mut c,
        &[
            (5, "N10 G01 X2 F6000\r\nN20 M6\r\n"),
            (50, "N30 G01 Y2\r\nN40 M30\r\n"),
        ],
        20_000,
    );
    let got = numbered_blocks(&ev);
    let want: Vec<(String, u64)> = [
        ("init.nc", 1),
        ("init.nc", 2),
        ("init.nc", 3),
        ("streaming.nc", 10),
        ("streaming.nc", 20),
        ("tool.nc", 4),
        ("tool.nc", 5),
        ("tool.nc", 6),
        ("streaming.nc", 30),
        ("streaming.nc", 40),
        ("final.nc", 7),
        ("final.nc", 8),
    ]
    .iter()
    .map(|(p, n)| (p.to_string(), *n))
    .collect();
    assert_eq!(got, want);
    let p = c.report().position;
    assert_eq!((p[0], p[1], p[2]), (3.0, 2.0, 5.0));
    assert!(ev.iter().any(|(_, e)| *e
        == EventKind::ProgramStart {
            prog: "streaming.nc".into(),
            stream: true
        }));
}

#[test]
fn without_implicit_subroutines_m6_is_an_ordinary_m_function_and_streams_work_as_before() {
    // Without m6_prog_file, M6 is an M function the channel list defines like any other.
    let i = Installation::new("m_synch[6] MOS\n");
    i.write("prg/tool.nc", "N4 G01 Z5 F6000\nN6 M17\n");
    let mut c = i.channel();
    start(&mut c, &tick(0), "streaming.nc");
    let ev = run(
        &mut c,
        &[(5, "N10 G01 X2 F6000\r\nN20 M6\r\nN30 M30\r\n")],
        20_000,
    );
    let progs: Vec<String> = blocks(&ev).into_iter().map(|(p, _)| p).collect();
    assert_eq!(progs, vec!["streaming.nc"; 3]);
    assert_eq!(c.report().position[0], 2.0);
    assert_eq!(c.report().position[2], 0.0);
}

#[test]
fn a_missing_implicit_subroutine_is_the_program_not_found_error() {
    let i = Installation::new("start_init_prog_file missing.nc\n");
    i.write("prg/p.nc", "N10 G01 X1 F6000\nN20 M30\n");
    let mut c = i.channel();
    start(&mut c, &tick(0), "p.nc");
    let ev = run(&mut c, &[], 1000);
    let msg = ev
        .iter()
        .find_map(|(_, e)| match e {
            EventKind::Error { msg, .. } => Some(msg.clone()),
            _ => None,
        })
        .expect("an error");
    assert!(msg.contains("missing.nc"), "{msg}");
    assert_eq!(c.report().position[0], 0.0);
}

#[test]
fn the_shipped_example_installation_runs_its_part() {
    let startup = Path::new("params/installation/listen/hochlauf.lis");
    let config = ncchannel::params::load(startup).unwrap_or_else(|e| panic!("{e}"));
    assert!(config.warnings.is_empty(), "{:#?}", config.warnings);
    assert_eq!(config.cnc_dir, Path::new("params/installation"));
    let ch = &config.channels[0];
    let names: Vec<&str> = ch.axes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["X", "Y", "Z"]);
    // achsmds3.lis: vb_max 250000 µm/s = 15000 mm/min, swe_neg -3000000 × 0.1 µm = -300 mm.
    assert_eq!(ch.axes[2].max_velocity_mm_per_min, 15000.0);
    assert_eq!(ch.axes[2].soft_limit_min_mm, -300.0);
    let mut c = ncchannel::channels(&config, true, &ncchannel::Loader::start())
        .unwrap()
        .remove(0);
    start(&mut c, &tick(0), "part.nc");
    let ev = run(&mut c, &[], 60_000);
    let progs: Vec<String> = blocks(&ev).into_iter().map(|(p, _)| p).collect();
    assert_eq!(progs.first().map(String::as_str), Some("init.nc"));
    assert!(progs.iter().any(|p| p == "toolchange.nc"));
    assert_eq!(progs.last().map(String::as_str), Some("final.nc"));
    // final.nc retracts the tool tip to Z100: with D1's length of 40 mm (werkz_d.lis) the
    // axis stands at 140; X and Y end at G54's offset (nullp_d.lis np_grp[1]).
    let p = c.report().position;
    assert_eq!((p[0], p[1], p[2]), (10.0, 20.0, 140.0));
    assert_eq!(
        config.channels[0].tool_list.as_deref(),
        Some(Path::new("params/installation/./listen/werkz_d.lis"))
    );
}

#[test]
fn m6_with_an_end_in_its_block_calls_the_tool_change_then_ends() {
    let i = Installation::new(IMPLICIT);
    implicit_programs(&i);
    // M6 and M30 in one block: tool.nc first, then final.nc (before M30), then the end; M6
    // and M17 in one block of a subroutine: tool.nc, then the return.
    i.write("prg/sub.nc", "N50 G01 Y1 F6000\nN51 M6 M17\n");
    i.write("prg/part.nc", "N10 L sub.nc\nN20 M6 M30\n");
    let mut c = i.channel();
    start(&mut c, &tick(0), "part.nc");
    let ev = run(&mut c, &[], 20_000);
    let got = numbered_blocks(&ev);
    let want: Vec<(String, u64)> = [
        ("init.nc", 1),
        ("init.nc", 2),
        ("init.nc", 3),
        ("part.nc", 10),
        ("sub.nc", 50),
        ("sub.nc", 51),
        ("tool.nc", 4),
        ("tool.nc", 5),
        ("tool.nc", 6),
        ("part.nc", 20),
        ("tool.nc", 4),
        ("tool.nc", 5),
        ("tool.nc", 6),
        ("final.nc", 7),
        ("final.nc", 8),
    ]
    .iter()
    .map(|(p, n)| (p.to_string(), *n))
    .collect();
    assert_eq!(got, want);
    assert_eq!(c.status().state, State::Ready);
    assert!(ev.iter().any(|(_, e)| *e
        == EventKind::ProgramEnd {
            prog: "part.nc".into(),
            end: ncchannel::report::event::ProgramEndKind::M30
        }));
}

/// P-CHAN-00006 names an axis with a letter outside X Y Z A B C: `W` (TF5200 channel
/// parameters, "Axis name" P-CHAN-00006). It takes the slot no name claims (Z's here), the
/// program writes `W…` or `W=…`, and `Z` names no axis of the channel.
#[test]
fn an_axis_the_channel_list_names_w_is_programmed_as_w() {
    let i = Installation::new("gruppe[0].achse[2].bezeichnung W\n");
    i.write(
        "prg/w.nc",
        "N10 G01 X10 W5 F6000\nN20 W = 2 * 3 Y1\nN30 G91 W-1\nN40 M30\n",
    );
    let mut c = i.channel();
    assert_eq!(
        c.apply(&tick(0), Op::Start("w.nc".into())),
        Reply::Command(Ok(()))
    );
    let ev = run(&mut c, &[], 20_000);
    end_tick(&ev);
    let named: Vec<(String, f64)> = c
        .report()
        .named_positions
        .into_iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    assert_eq!(
        named,
        [
            ("X".to_string(), 10.0),
            ("Y".to_string(), 1.0),
            ("W".to_string(), 5.0)
        ]
    );
    // Z is no axis of this channel, nor is U.
    for (name, text) in [
        ("z.nc", "N10 G01 Z20 F6000\nN20 M30\n"),
        ("u.nc", "N10 G01 U20 F6000\nN20 M30\n"),
    ] {
        i.write(&format!("prg/{name}"), text);
        let mut c = i.channel();
        assert_eq!(
            c.apply(&tick(0), Op::Start(name.into())),
            Reply::Command(Ok(()))
        );
        let ev = run(&mut c, &[], 20_000);
        assert!(
            ev.iter()
                .any(|(_, e)| matches!(e, EventKind::Error { code: 20200, .. })),
            "{name}: {ev:#?}"
        );
    }
    // A longer name with such a letter takes `=`: `U1` in X's slot, which no name claims.
    let i = Installation::new("gruppe[0].achse[0].bezeichnung U1\n");
    i.write("prg/u1.nc", "N10 G01 U1=7 Y2 F6000\nN20 M30\n");
    let mut c = i.channel();
    assert_eq!(
        c.apply(&tick(0), Op::Start("u1.nc".into())),
        Reply::Command(Ok(()))
    );
    let ev = run(&mut c, &[], 20_000);
    end_tick(&ev);
    let named: Vec<(String, f64)> = c
        .report()
        .named_positions
        .into_iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    assert_eq!(named[0], ("U1".to_string(), 7.0));
}

/// P-CHAN-00006 names an axis `X1` (a name of more than one character): the program writes
/// `X1=…`, and the axis takes X's slot (TF5200 programming manual, "Axis commands").
#[test]
fn an_axis_named_x1_in_the_channel_list_is_programmed_as_x1_equals() {
    let i = Installation::new(
        "gruppe[0].achse[0].bezeichnung X1\ngruppe[0].achse[2].bezeichnung Z_ACHSE\n",
    );
    i.write(
        "prg/named.nc",
        "N10 G01 X1=20 Y5 F6000\nN20 Z_ACHSE = 2 * 3\nN30 M30\n",
    );
    let mut c = i.channel();
    assert_eq!(
        c.apply(&tick(0), Op::Start("named.nc".into())),
        Reply::Command(Ok(()))
    );
    let ev = run(&mut c, &[], 20_000);
    end_tick(&ev);
    let named: Vec<(String, f64)> = c
        .report()
        .named_positions
        .into_iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    assert_eq!(
        named,
        [
            ("X1".to_string(), 20.0),
            ("Y".to_string(), 5.0),
            ("Z_ACHSE".to_string(), 6.0)
        ]
    );
    // X alone is no axis of this channel.
    i.write("prg/bare.nc", "N10 G01 X20 F6000\nN20 M30\n");
    let mut c = i.channel();
    assert_eq!(
        c.apply(&tick(0), Op::Start("bare.nc".into())),
        Reply::Command(Ok(()))
    );
    let ev = run(&mut c, &[], 20_000);
    assert!(
        ev.iter()
            .any(|(_, e)| matches!(e, EventKind::Error { code: 20200, .. })),
        "{ev:#?}"
    );
    // Two axes in X's slot are refused by the parameter check.
    let i = Installation::new("gruppe[0].achse[1].bezeichnung X2\n");
    let e = ncchannel::params::load(&i.startup())
        .unwrap_err()
        .to_string();
    assert!(e.contains("takes the slot of axis `X`"), "{e}");
}
