//! The simulated PLC in the soak: the shipped scenario `plc.toml` holds the technology
//! invariants and its figures are pinned by seed; a reset while a function waits drops it and
//! the next program runs; the check fails when the rule is broken (a PLC that acknowledges a
//! function twice is not possible through the door, so the checker's own unit tests in
//! `src/soak/invariants.rs` feed it crafted observations).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use ncchannel::channel::techno::TechnoSeen;
use ncchannel::machine::plc::{PlcConfig, SimulatedPlc};
use ncchannel::machine::{Machine, Op, Reply, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::runtime::{Clock, Runtime, Tick};
use ncchannel::soak::scenario::{Length, Scenario};
use ncchannel::soak::{run, Options};
use ncchannel::vocab::techno::TechnoKind;

fn soak_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("params/soak")
}

fn blocks(n: u64, seed: Option<u64>) -> Options {
    Options {
        length: Some(Length {
            blocks: Some(n),
            ..Length::default()
        }),
        seed,
        ..Options::default()
    }
}

#[test]
fn the_plc_scenario_holds_and_its_figures_are_pinned_by_seed() {
    let s = Scenario::load(&soak_dir().join("plc.toml")).unwrap();
    let r = run(&s, &blocks(3000, None)).unwrap();
    for v in &r.invariants {
        assert!(v.held || v.name == "memory steady", "{v:?}");
    }
    assert!(
        r.invariants
            .iter()
            .any(|v| v.name.starts_with("no block starts before")),
        "the technology verdicts are reported"
    );
    let c = &r.channels[0];
    let p = c.plc.as_ref().expect("the PLC's counters");
    let f = p.functions;
    // Seed 6, 3000 blocks: pinned. Every function output is acknowledged, dropped by one of
    // the resets, or open at the end.
    assert_eq!(
        (c.blocks, c.resets, c.checksum.as_str(), r.ticks),
        (3000, 9, "03adfb6782f5e110", 376_617)
    );
    assert_eq!(
        (
            f.output,
            f.acknowledged,
            f.dropped,
            f.dropped_unoutput,
            p.open_at_end
        ),
        (1635, 1631, 3, 0, 1)
    );
    assert_eq!(f.output, f.acknowledged + f.dropped + p.open_at_end);
    assert_eq!((p.late, p.unanswered), (233, 0));
    assert_eq!(f.waited_starts, 550);
    assert!(
        (100..=500).contains(&f.max_output_to_start_ms),
        "M302 waits 50 … 150 ms, late answers 250 ms more: {}",
        f.max_output_to_start_ms
    );
    // Same seed, same run; another seed draws other delays and faults.
    let again = run(&s, &blocks(3000, None)).unwrap();
    assert_eq!(again.channels[0].checksum, c.checksum);
    assert_eq!(again.channels[0].plc, c.plc);
    let other = run(&s, &blocks(3000, Some(7))).unwrap();
    assert_ne!(other.channels[0].plc, c.plc);
}

#[test]
fn a_scenario_without_a_plc_reports_no_technology_verdicts() {
    let s = Scenario::load(&soak_dir().join("stream_resets.toml")).unwrap();
    let r = run(&s, &blocks(2000, None)).unwrap();
    assert!(r.channels[0].plc.is_none());
    assert!(
        !r.invariants.iter().any(|v| v.name.contains("technology")),
        "held and not reported without a PLC (the pinned reports keep their shape)"
    );
}

/// The tick the runtime is at, for requests between its runs.
fn now(rt: &Runtime<Machine>) -> Tick {
    Tick {
        index: rt.ticks(),
        period: rt.period(),
        time: rt.time(),
        clock: Clock::Virtual,
    }
}

fn x(m: &Machine) -> f64 {
    m.channels()[0]
        .status()
        .positions
        .iter()
        .find(|(a, _)| *a == 'X')
        .map_or(f64::NAN, |(_, v)| *v)
}

/// Start the streaming program and write `text` into it.
fn stream(rt: &mut Runtime<Machine>, text: &str) {
    let t = now(rt);
    let m = rt.cycle_mut();
    assert_eq!(
        m.apply(&t, 1, Op::Start("stream1.nc".into())),
        Reply::Command(Ok(()))
    );
    // The stream interface takes lines ended by CR LF.
    let text = text.replace('\n', "\r\n");
    let r = m.apply(&t, 1, Op::WriteStream(Arc::from(text.as_bytes())));
    assert_eq!(r, Reply::Stream(Ok(())));
}

#[test]
fn a_reset_while_a_function_waits_drops_it_and_the_next_program_runs() {
    let config = ncchannel::params::load(&soak_dir().join("startup.lis")).unwrap();
    let channels = ncchannel::channels(&config, false, &ncchannel::Loader::start()).unwrap();
    let mut m = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    m.attach_plc(SimulatedPlc::new(
        1,
        PlcConfig {
            delay_ms: [10, 10],
            overrides: vec![(TechnoKind::M, Some(302), [300, 300])],
            ..PlcConfig::default()
        },
    ));
    let (mut rt, _tx) = Runtime::new(m, Duration::from_millis(1), Clock::Virtual);
    let t = now(&rt);
    assert_eq!(
        rt.cycle_mut().apply(&t, 1, Op::ObserveTechno(true)),
        Reply::Done
    );
    stream(&mut rt, "N10 G90 G01 X1 F6000\nN20 M302\nN30 G01 X2\nM30\n");
    rt.run(Some(300));
    let units = rt.cycle().channels()[0].status().techno;
    assert!(units.plc_present);
    assert!(units.std[0].please, "M302 waits in its unit");
    let st = rt.cycle().channels()[0].status();
    assert!(
        (x(rt.cycle()) - 1.0).abs() < 1e-9,
        "the axes stand before N30: {:?} {:?} {:?}",
        st.positions,
        st.state,
        st.last_error
    );

    let t = now(&rt);
    assert_eq!(rt.cycle_mut().apply(&t, 1, Op::Reset), Reply::Done);
    let units = rt.cycle().channels()[0].status().techno;
    assert!(
        units.std.iter().all(|u| !u.please),
        "the reset cleared the units"
    );
    let seen = match rt.cycle_mut().apply(&t, 1, Op::DrainTechno) {
        Reply::TechnoSeen { seen, lost: 0 } => seen,
        r => panic!("{r:?}"),
    };
    assert!(
        matches!(seen.last(), Some(TechnoSeen::Dropped { .. })),
        "{seen:?}"
    );

    rt.cycle_mut().set_stop_when(StopWhen::ProgramsFinished);
    stream(&mut rt, "N10 M302\nN20 G01 X5 F6000\nM30\n");
    rt.run(Some(5000));
    let m = rt.cycle();
    let st = m.channels()[0].status();
    assert_eq!(
        m.finishes()[0],
        Some(ncchannel::channel::Finish::Ended),
        "{:?}",
        st.last_error
    );
    assert!((x(m) - 5.0).abs() < 1e-9);
    let r = m.channels()[0].report().techno;
    assert_eq!((r.output, r.acknowledged, r.dropped_by_reset), (2, 1, 1));
    let plc = m.plcs()[0].stats();
    assert_eq!((plc.taken, plc.acknowledged, plc.dropped), (2, 1, 1));
}
