//! Technology functions against the TF5200 examples of the synchronisation types ("Examples of
//! the synchronisation methods in connection with motions"): the block times prove when the
//! motion started relative to the output and the acknowledgement. No PLC is present, so the
//! channel acknowledges each unit after the function's process time (`m_prozess_zeit`).

use serde_json::Value;

use super::support::{Rig, RunResult};

/// The manual's program: M25 in N40, a rapid move between two others.
const EXAMPLE: &str = "N20 G00 X25\nN30 X50\nN40 X75 M25\nN50 G01 X100 F2000\nN60 X125 Z100\nM30\n";

/// Process time of M25 in these tests, s.
const PROCESS_S: f64 = 0.5;

fn rig_with(m_synch: &str) -> Rig {
    let rig = Rig::new();
    let list = format!(
        "streaming_prog_file streaming.nc\nm_synch[25] {m_synch}\nm_prozess_zeit[25] {}\n",
        (PROCESS_S * 1e6) as u64
    );
    std::fs::write(rig.startup().with_file_name("channel1.lis"), list).unwrap();
    rig
}

fn run(m_synch: &str) -> RunResult {
    let rig = rig_with(m_synch);
    rig.program("example.nc", EXAMPLE);
    let r = rig.run("example.nc", None, 200_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    r
}

/// Channel time of the `block` event of the block numbered `n`.
fn block_t(r: &RunResult, n: u64) -> f64 {
    r.of("block")
        .into_iter()
        .find(|e| e["n"] == n)
        .and_then(|e| e["t"].as_f64())
        .unwrap_or_else(|| panic!("no block N{n}: {}", r.log))
}

fn only<'a>(r: &'a RunResult, ev: &str) -> &'a Value {
    let v = r.of(ev);
    assert_eq!(v.len(), 1, "one {ev}: {}", r.log);
    v[0]
}

fn t(e: &Value) -> f64 {
    e["t"].as_f64().unwrap()
}

/// Channel time the program took.
fn end_t(r: &RunResult) -> f64 {
    t(only(r, "program_end"))
}

#[test]
fn mvs_svs_the_motion_of_its_block_starts_only_after_the_acknowledgement() {
    let r = run("MVS_SVS");
    let out = only(&r, "techno_output");
    assert_eq!(out["kind"], "m");
    assert_eq!(out["number"], 25);
    assert_eq!(out["sync"], "MVS_SVS");
    assert_eq!(out["unit"], 0);
    let ack = only(&r, "techno_acknowledged");
    let waited = ack["waited_s"].as_f64().unwrap();
    assert!((waited - PROCESS_S).abs() < 0.002, "{waited}");
    // Output when N40 is reached (N30 done, the axes at rest), motion of N40 after the
    // acknowledgement.
    assert!(t(out) >= block_t(&r, 30));
    assert!(block_t(&r, 40) >= t(ack) - 1e-9, "{}", r.log);
    assert!(block_t(&r, 40) - t(out) >= PROCESS_S - 1e-9);
}

#[test]
fn mvs_sns_outputs_before_the_motion_and_waits_at_the_block_end() {
    let r = run("MVS_SNS");
    let out = only(&r, "techno_output");
    let ack = only(&r, "techno_acknowledged");
    // The motion of N40 does not wait: it starts when the function goes out.
    assert!((block_t(&r, 40) - t(out)).abs() < 0.002, "{}", r.log);
    // N50 waits for the acknowledgement (the rapid N40 takes less than the process time).
    assert!(block_t(&r, 50) >= t(ack) - 1e-9, "{}", r.log);
    assert!(block_t(&r, 50) - block_t(&r, 40) >= PROCESS_S - 1e-9);
}

#[test]
fn mns_sns_outputs_after_the_motion_and_waits_then() {
    let r = run("MNS_SNS");
    let out = only(&r, "techno_output");
    let ack = only(&r, "techno_acknowledged");
    // Output only once N40's 25 mm are done: later than N40's start by its motion time.
    let n40_motion = t(out) - block_t(&r, 40);
    assert!(n40_motion > 0.01, "{}", r.log);
    assert!(block_t(&r, 50) >= t(ack) - 1e-9);
    assert!(
        (block_t(&r, 50) - t(out) - PROCESS_S).abs() < 0.005,
        "{}",
        r.log
    );
}

#[test]
fn mos_is_output_and_the_motion_goes_on_without_waiting() {
    let with = run("MOS");
    let out = only(&with, "techno_output");
    assert!((block_t(&with, 40) - t(out)).abs() < 0.002);
    // The program runs exactly as without the function: no wait anywhere.
    let rig = rig_with("NO_SYNCH");
    rig.program("example.nc", EXAMPLE);
    let without = rig.run("example.nc", None, 200_000);
    assert_eq!(without.of("techno_output").len(), 0, "NO_SYNCH: not output");
    assert!((end_t(&with) - end_t(&without)).abs() < 1e-9);
}

#[test]
fn a_wait_costs_channel_time_the_program_takes_longer_by_the_wait() {
    let svs = run("MVS_SVS");
    let rig = rig_with("NO_SYNCH");
    rig.program("example.nc", EXAMPLE);
    let none = rig.run("example.nc", None, 200_000);
    let extra = end_t(&svs) - end_t(&none);
    // At least the process time; N30 now ends at rest and N40 starts from rest.
    assert!(extra >= PROCESS_S, "{extra}");
    assert!(extra < PROCESS_S + 0.5, "{extra}");
}

#[test]
fn an_m_function_the_channel_list_does_not_define_is_20157_and_an_h_20162() {
    let rig = rig_with("MVS_SVS");
    rig.program("m.nc", "N10 G01 X1 F1000\nN20 M26\nM30\n");
    let r = rig.run("m.nc", None, 10_000);
    assert_eq!(r.error_codes(), vec![20157], "{}", r.log);
    rig.program("h.nc", "N10 H7=2\nM30\n");
    let r = rig.run("h.nc", None, 10_000);
    assert_eq!(r.error_codes(), vec![20162], "{}", r.log);
}

#[test]
fn the_kernels_internal_m_functions_need_no_entry_and_are_not_output() {
    let rig = rig_with("MVS_SVS");
    rig.program("i.nc", "N10 M3 S1000\nN20 G01 X1 F1000\nN30 M5\nM30\n");
    let r = rig.run("i.nc", None, 10_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    assert_eq!(r.of("techno_output").len(), 0, "{}", r.log);
}

#[test]
fn a_value_goes_with_its_function_and_several_functions_share_the_units_of_their_block() {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "streaming_prog_file streaming.nc\nm_synch[200] MVS_SVS\nm_synch[8] MVS_SVS\nh_synch[7] MOS\n\
         m_prozess_zeit[200] 100000\nm_prozess_zeit[8] 200000\n",
    )
    .unwrap();
    rig.program("v.nc", "N10 M200=1200 M8 H7=2\nN20 G01 X1 F1000\nM30\n");
    let r = rig.run("v.nc", None, 10_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    let outs = r.of("techno_output");
    let got: Vec<(String, u64, Option<i64>, u64)> = outs
        .iter()
        .map(|e| {
            (
                e["kind"].as_str().unwrap().to_string(),
                e["number"].as_u64().unwrap(),
                e["value"].as_i64(),
                e["unit"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        got,
        vec![
            ("m".into(), 200, Some(1200), 0),
            ("m".into(), 8, None, 1),
            ("h".into(), 7, Some(2), 2)
        ]
    );
    // One group: all output in the same tick; N20 moves after the slower of the two waits.
    assert!(outs.iter().all(|e| t(e) == t(outs[0])));
    assert!(block_t(&r, 20) - t(outs[0]) >= 0.2 - 1e-9, "{}", r.log);
    assert_eq!(r.of("techno_acknowledged").len(), 3);
}

#[test]
fn a_program_changes_a_functions_type_through_v_g_m_fct_synch() {
    let rig = rig_with("MVS_SVS");
    let prog = "V.G.M_FCT[25].SYNCH = 1\n\
                $IF V.G.M_FCT[25].SYNCH == 1\n#MSG [\"M25 is MOS now\"]\n$ENDIF\n\
                N20 G00 X25\nN30 X50\nN40 X75 M25\nN50 G01 X100 F2000\nM30\n";
    rig.program("v.nc", prog);
    let r = rig.run("v.nc", None, 200_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    assert_eq!(only(&r, "techno_output")["sync"], "MOS");
    assert_eq!(only(&r, "message")["text"], "M25 is MOS now");
    // MOS does not wait: N40's motion starts with the output.
    assert!((block_t(&r, 40) - t(only(&r, "techno_output"))).abs() < 0.002);
    // A value that is no modelled type is refused at the assignment.
    rig.program("bad.nc", "G01 X1 F1000\nV.G.H_FCT[7].SYNCH = 3\nM30\n");
    let r = rig.run("bad.nc", None, 10_000);
    assert_eq!(r.error_codes(), vec![900132], "{}", r.log);
}

/// The late-synchronisation examples: two functions with a 2 s process time, output early,
/// synchronised only where the manual's program says.
fn late_rig(m_synch: &str) -> Rig {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        format!(
            "streaming_prog_file streaming.nc\nm_synch[24] {m_synch}\nm_synch[25] {m_synch}\n\
             m_prozess_zeit[24] 2000000\nm_prozess_zeit[25] 2000000\n"
        ),
    )
    .unwrap();
    rig
}

#[test]
fn mvs_slm_synchronises_before_the_next_feed_motion_block() {
    let rig = late_rig("MVS_SLM");
    rig.program(
        "slm.nc",
        "N05 M24\nN10 M25 G00 X25\nN20 X50\nN30 X75\nN40 X100\nN50 G01 X125 F2000\nN60 Z100\nM30\n",
    );
    let r = rig.run("slm.nc", None, 200_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    let outs = r.of("techno_output");
    assert_eq!(outs.len(), 2);
    assert!(outs
        .iter()
        .all(|e| e["late"] == true && e["sync"] == "MVS_SLM"));
    let last_ack = r
        .of("techno_acknowledged")
        .iter()
        .map(|e| t(e))
        .fold(0.0, f64::max);
    // The rapid blocks run on while the PLC works; the feed block N50 waits for both.
    assert!(block_t(&r, 40) < last_ack, "{}", r.log);
    assert!(block_t(&r, 50) >= last_ack - 1e-9, "{}", r.log);
}

#[test]
fn mvs_slp_synchronises_at_expl_syn() {
    let rig = late_rig("MVS_SLP");
    rig.program(
        "slp.nc",
        "N05 M24 G00 X25\nN10 M25\nN20 X50\nN30 X75\nN40 X100\nN50 G01 X125 F2000\n\
         N60 #EXPL SYN\nN70 G00 X0\nN80 X0 Y0\nM30\n",
    );
    let r = rig.run("slp.nc", None, 200_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    let last_ack = r
        .of("techno_acknowledged")
        .iter()
        .map(|e| t(e))
        .fold(0.0, f64::max);
    assert_eq!(r.of("techno_acknowledged").len(), 2);
    // Even the feed block N50 does not wait (that is MVS_SLM's point); N70 after #EXPL SYN does.
    assert!(block_t(&r, 50) < last_ack, "{}", r.log);
    assert!(block_t(&r, 70) >= last_ack - 1e-9, "{}", r.log);
}

/// The TwinCAT CNC example of "Synchronization types MET_SVS, MEP_SVS": M96 in N45 is output
/// 25 mm (MEP_SVS, `m_pre_outp` 250000 × 0.1 µm) or 0.3 s (MET_SVS, 300000 µs) before the
/// synchronisation point X40, while N20 still moves.
fn pre_output_run(m_synch: &str, pre: u32) -> RunResult {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        format!(
            "streaming_prog_file streaming.nc\nm_synch[96] {m_synch}\nm_pre_outp[96] {pre}\n\
             m_prozess_zeit[96] 300000\n"
        ),
    )
    .unwrap();
    rig.program(
        "pre.nc",
        "N10 G01 X10 G90 F5000\nN20 X20\nN30 X30\nN40 X40\nN45 M96\nN50 X80\nM30\n",
    );
    let r = rig.run("pre.nc", None, 200_000);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{}", r.log);
    r
}

#[test]
fn mep_svs_and_met_svs_go_out_before_the_synchronisation_point_while_the_axes_still_move() {
    let svs = pre_output_run("MVS_SVS", 0);
    for (sync, pre) in [("MEP_SVS", 250_000), ("MET_SVS", 300_000)] {
        let r = pre_output_run(sync, pre);
        let out = only(&r, "techno_output");
        let ack = only(&r, "techno_acknowledged");
        assert_eq!(out["sync"], sync);
        // Out while N20 moves (25 mm or about 0.3 s before X40 is X15), not at N45.
        assert!(
            t(out) > block_t(&r, 20) && t(out) < block_t(&r, 30),
            "{sync}: {}",
            r.log
        );
        // N50 still starts only after the acknowledgement ...
        assert!(block_t(&r, 50) >= t(ack) - 1e-9, "{sync}: {}", r.log);
        // ... which the PLC's time, overlapping the motion, made sooner than MVS_SVS's.
        assert!(
            end_t(&r) < end_t(&svs) - 0.2,
            "{sync}: {} vs {}",
            end_t(&r),
            end_t(&svs)
        );
    }
}
