//! Language behaviours real programs and the TF5200 programming manual's examples meet, each
//! answered as the kernel answers it: the id it reports, or the position it reaches.

use crate::support::{Rig, RunResult};
use ncchannel::channel::Finish;

/// `text` run from a file on `rig`.
fn run(rig: &Rig, text: &str) -> RunResult {
    rig.program("t.nc", text);
    rig.run("t.nc", None, 1_000_000)
}

/// `text` fails with the one error `code`.
fn fails(rig: &Rig, text: &str, code: u64) -> RunResult {
    let r = run(rig, text);
    assert_eq!(r.finish, Some(Finish::Error), "{text}\n{}", r.log);
    assert_eq!(r.error_codes(), [code], "{text}\n{}", r.log);
    r
}

/// `text` runs to its end without an error.
fn ends(rig: &Rig, text: &str) -> RunResult {
    let r = run(rig, text);
    assert_eq!(r.finish, Some(Finish::Ended), "{text}\n{}", r.log);
    assert_eq!(r.error_codes(), Vec::<u64>::new(), "{text}\n{}", r.log);
    r
}

#[test]
fn the_kernels_ids_for_a_negative_root_feed_and_a_missing_program_end() {
    let rig = Rig::new();
    // 20398: square root of a negative value.
    fails(&rig, "P1 = SQRT[-1]\nM30\n", 20398);
    // 20176: negative F. F0 is a word the kernel takes; a feed move at it is 20008.
    fails(&rig, "G01 X10 F-5\nM30\n", 20176);
    fails(&rig, "F0\nG01 X10\nM30\n", 20008);
    // 21129: the main program's file ends without M30/M02.
    fails(&rig, "G01 X10 F6000\n", 21129);
}

#[test]
fn the_kernels_ids_for_words_programmed_twice() {
    let rig = Rig::new();
    // 20205: a circle centre parameter twice.
    fails(&rig, "G02 X10 I5 I5 J0 F100\nM30\n", 20205);
    // 20765 (TF5200 diagnosis "Double-programmed M-function."): the same M function twice;
    // two different ones stay allowed.
    fails(&rig, "M30 M30\n", 20765);
    assert_eq!(
        ncchannel::lang::parse_block("M7 M7").unwrap_err().code,
        20765
    );
    ends(&rig, "M7 M8\nM30\n");
    // T twice keeps its own id.
    fails(&rig, "T1 T2\nM30\n", 900135);
}

#[test]
fn u_v_w_twice_in_a_block_is_an_axis_twice() {
    // TF5200 "Axis commands": U V W are axis letters like X Y Z A B C.
    for (line, col) in [("W1 W2", 4), ("U=1 U=2", 5)] {
        let e = ncchannel::lang::parse_block(line).unwrap_err();
        assert_eq!((e.code, e.col), (20203, col), "{line}");
    }
}

#[test]
fn an_h_function_outside_the_numbers_is_the_kernels_undefined_h() {
    let rig = Rig::new();
    fails(&rig, "H70000\nM30\n", 20162);
    fails(&rig, "H5\nM30\n", 20162);
}

#[test]
fn under_g161_i_j_k_are_the_circle_centre_in_program_coordinates() {
    let rig = Rig::new();
    // TF5200 "Specifying centre point for circle definition (G161/G162)": the centre (0, 0)
    // written absolutely; the half circle from (10, 0) ends at (-10, 0) and back.
    ends(
        &rig,
        "G01 X10 Y0 F6000\nG161 G02 X-10 Y0 I0 J0\nG03 X10 Y0 I0 J0\nM30\n",
    );
    // Under G162, the initial state a new program starts in, I0 J0 puts the centre on the
    // start point: no circle.
    fails(&rig, "G01 X10 Y0 F6000\nG02 X-10 Y0 I0 J0\nM30\n", 900130);
    // G162 in the program turns G161 off.
    let r = ends(&rig, "G01 X10 Y0 F6000\nG161\nG162 G02 X-10 I-10 J0\nM30\n");
    assert!((r.position('X') + 10.0).abs() < 1e-6, "{}", r.log);
    // The programmer's coordinates: after G92 makes machine X20 program X10, the centre I0 J0
    // is machine (10, 0), and the half circle ends at machine X0.
    let r = ends(
        &rig,
        "G01 X20 Y0 F6000\nG92 X10 Y0\nG161 G02 X-10 I0 J0\nM30\n",
    );
    assert!(r.position('X').abs() < 1e-6, "{}", r.log);
    assert!(r.position('Y').abs() < 1e-6, "{}", r.log);
}

#[test]
fn a_function_may_follow_an_address_letter() {
    let rig = Rig::new();
    // TF5200 "Axis commands": "X <int, double, expr>", as `Z SIN [30]` and `A SQRT [2]/2`:
    // after the address letter the expression stands without the word's brackets, with or
    // without blanks, and runs on through its operators.
    let r = ends(
        &rig,
        "P1 = 6\nP2 = 16\nG01 X SIN [P1 * 5] Y-SQRT[P2] Z SQRT [4]/2 F6000\nM30\n",
    );
    assert!((r.position('X') - 0.5).abs() < 1e-9, "{}", r.log);
    assert!((r.position('Y') + 4.0).abs() < 1e-9, "{}", r.log);
    assert!((r.position('Z') - 1.0).abs() < 1e-9, "{}", r.log);
    assert_eq!(
        ncchannel::lang::check_program("G01 X SIN [30] F100\nM30\n"),
        []
    );
    // A name that is no function, or a function without its bracket, is no value.
    fails(&rig, "G01 X FOO[1] F100\nM30\n", 20200);
    fails(&rig, "G01 X SIN 30 F100\nM30\n", 20200);
    // M, G and H still take literal numbers only.
    fails(&rig, "M SIN[1]\nM30\n", 20157);
}

/// The codes of the run's warning events, in order.
fn warnings(r: &RunResult) -> Vec<u64> {
    r.of("warning")
        .iter()
        .map(|e| e["code"].as_u64().unwrap_or(0))
        .collect()
}

#[test]
fn neutral_transformations_run_as_no_ops_with_a_warning() {
    let rig = Rig::new();
    // TF5200 programming manual: "Combined preselection and activation" (#TRAFO [OFF|NONE]),
    // "Separate preselection and activation" (#KIN ID [NONE]), "Definition of a machining
    // coordinate system (CS)" (#CS DEF / ON / OFF).
    for (text, n) in [
        ("#TRAFO OFF", 1),
        ("#TRAFO [NONE, NONE]", 1),
        ("#TRAFO [OFF]", 1),
        ("#KIN ID [NONE]", 1),
        ("#KIN ID [NONE, NONE]", 1),
        ("#CS OFF", 1),
        ("#CS OFF ALL", 1),
        ("#CS DEF [1] [0,0,0,0,0,0]\n#CS ON [1]\n#CS OFF", 3),
        ("#CS ON [2] [0, 0, P1, 0, 0, 0]\n#CS OFF\n#CS ON [2]", 3),
        ("#CS DEF [0,0,0,0,0,0]\n#CS ON", 2),
    ] {
        let r = ends(&rig, &format!("P1 = 0\nG01 X10 F6000\n{text}\nY5\nM30\n"));
        assert_eq!(warnings(&r), vec![900137; n], "{text}\n{}", r.log);
        assert!((r.position('X') - 10.0).abs() < 1e-9, "{text}");
        assert!((r.position('Y') - 5.0).abs() < 1e-9, "{text}");
    }
}

#[test]
fn a_transformation_that_would_move_the_path_stays_refused() {
    let rig = Rig::new();
    for text in [
        "#CS ON [1] [10,0,0,0,0,0]",
        "#CS DEF [1] [0,0,0,0,0,45]",
        // Selecting a CS never defined.
        "#CS ON [2]",
        "#CS ON",
        "#TRAFO ON",
        "#TRAFO [86]",
        "#KIN ID [86]",
        "#CS ADD [ICS] [0,0,0,0,0,0]",
    ] {
        let r = fails(&rig, &format!("G01 X10 F6000\n{text}\nY5\nM30\n"), 900133);
        assert!((r.position('Y')).abs() < 1e-9, "{text}");
    }
    // Three values are no CS definition ncchannel knows: refused by name too.
    fails(&rig, "#CS DEF [1] [0,0,0]\nM30\n", 900133);
    // A shift computed at run time is refused when the block runs; a literal one already by
    // `check`.
    fails(&rig, "P1 = 10\n#CS ON [1] [P1,0,0,0,0,0]\nM30\n", 900133);
    let d = ncchannel::lang::check_program("#CS ON [1] [10,0,0,0,0,0]\nM30\n");
    assert_eq!(
        d.iter()
            .map(|d| (d.line, d.col, d.code))
            .collect::<Vec<_>>(),
        [(1, 1, 900133)]
    );
}

/// (kind, number, value) of the run's technology outputs.
fn outputs(r: &RunResult) -> Vec<(String, u64, Option<i64>)> {
    r.of("techno_output")
        .iter()
        .map(|e| {
            (
                e["kind"].as_str().unwrap_or("").to_string(),
                e["number"].as_u64().unwrap_or(0),
                e["value"].as_i64(),
            )
        })
        .collect()
}

#[test]
fn axis_and_spindle_brackets_hand_their_functions_to_the_units() {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "streaming_prog_file streaming.nc\nm_synch[54] MOS\nm_synch[63] MOS\nh_synch[20] MOS\n\
         spindel[0].s_synch MOS\n",
    )
    .unwrap();
    // TF5200 "Programming in spindle-specific syntax" and "User-specific M/H function for
    // spindles": the speed REV, the spindle's M3 and its own functions with their values.
    let r = ends(
        &rig,
        "P1 = 3\nG01 X10 F6000 X[M54=P1]\nS[REV 1000 M03 M63=-789 H20]\nS[REV=500]\nM30\n",
    );
    assert!((r.position('X') - 10.0).abs() < 1e-9);
    assert_eq!(
        outputs(&r)
            .into_iter()
            .filter(|(k, _, _)| k != "s")
            .collect::<Vec<_>>(),
        [
            ("m".to_string(), 54, Some(3)),
            ("m".to_string(), 63, Some(-789)),
            ("h".to_string(), 20, None)
        ],
        "{}",
        r.log
    );
    let speeds: Vec<Option<i64>> = outputs(&r)
        .into_iter()
        .filter(|(k, _, _)| k == "s")
        .map(|(_, _, v)| v)
        .collect();
    assert_eq!(speeds, [Some(1000), Some(500)], "{}", r.log);
    // An M number the channel list does not define is refused as a plain M word is.
    fails(&rig, "X[M55]\nM30\n", 20157);
    fails(&rig, "S[REV 100 M64=1]\nM30\n", 20157);
    // TF5200 diagnosis ID 20991 "Negative spindle speed not permitted." in S[...].
    fails(&rig, "S[REV -5 M3]\nM30\n", 20991);
    // What a bracket may hold besides M, H and REV is not modelled.
    fails(&rig, "S[M3 POS45]\nM30\n", 900133);
    // One M number once per scope: the channel's, an axis's and the spindle's are three
    // (TF5200 diagnosis ID 20765, whose example this is); twice in one bracket is 20765.
    let r = ends(&rig, "M54 X[M54] S[M54]\nM30\n");
    assert_eq!(outputs(&r).len(), 3, "{}", r.log);
    fails(&rig, "S[M54 M54]\nM30\n", 20765);
    // The bracket names the functions, not the axis: X may still move in the block.
    ends(&rig, "X[M54] X5 F6000 G01\nM30\n");
    // The brackets print as written, so the printed block reads back (and keeps M54 twice in
    // two scopes legal).
    let b = ncchannel::lang::parse_block("M54 X[M54=P1] S[REV 1000 M03 M63=-789]").unwrap();
    let printed = b.to_string();
    assert_eq!(printed, "M54 X[M54=P1] S[M3 M63=-789 REV1000]");
    assert_eq!(
        ncchannel::lang::parse_block(&printed).unwrap().to_string(),
        printed
    );
    // A bracket that is an expression stays one.
    let r = ends(&rig, "P1 = 2\nG01 X[P1*2] F6000\nM30\n");
    assert!((r.position('X') - 4.0).abs() < 1e-9);
}

#[test]
fn g160_without_an_axis_is_the_kernels_warning_and_the_program_goes_on() {
    let rig = Rig::new();
    // TwinCAT CNC diagnosis ID 20003 (class 1: processing continues), whose example is
    // `G160=2` without the axes of `G160=2 X1 Z1`.
    let r = ends(&rig, "G01 X10 F6000\nG160=2\nY5\nM30\n");
    assert_eq!(warnings(&r), [20003], "{}", r.log);
    assert!((r.position('Y') - 5.0).abs() < 1e-9);
    // With its axes it would offset them, which ncchannel does not model.
    fails(&rig, "G160=2 X1 Z1\nM30\n", 900133);
}

#[test]
fn g63_with_spindle_speed_0_is_the_kernels_20007() {
    let rig = Rig::new();
    // TF5200 diagnosis ID 20007 "Spindle speed is 0.", example `G63 Z10 F300 S0`; another
    // G63 is refused by name: ncchannel does not model tapping.
    fails(&rig, "G63 Z10 F300 S0\nM30\n", 20007);
    fails(&rig, "S0 G63 Z10 F300\nM30\n", 20007);
    fails(&rig, "G63 Z10 F300 S17\nM30\n", 900133);
    let d = ncchannel::lang::check_program("G63 Z10 F300 S0\nM30\n");
    assert_eq!(
        d.iter()
            .map(|d| (d.line, d.col, d.code))
            .collect::<Vec<_>>(),
        [(1, 14, 20007)]
    );
}
