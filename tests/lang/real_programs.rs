//! Constructs of real programs (ISG's SDK examples, CAM and printer post-processor output,
//! ISG's editor test programs) that the kernel runs: `#MSG` with formatted values, implicit
//! subroutine calls G800–G819 with parameters, and the inert tool and channel commands. Each
//! is run from a file and from the stream, and `ncchannel check` (`check_program`) finds what
//! a run finds, at the same line and column.

use crate::support::{feeder, Rig, RunResult};
use ncchannel::channel::Finish;
use ncchannel::lang::codes;
use ncchannel::lang::msg::{MAX_MSG_CHARS, MAX_MSG_VALUES};
use ncchannel::lang::{check_program, parse_block};

/// Run `text` as `t.nc` from a file and as the streaming program; both results.
fn both(rig: &Rig, text: &str) -> [RunResult; 2] {
    rig.program("t.nc", text);
    let file = rig.run("t.nc", None, 2_000_000);
    let stream = rig.run(
        "streaming.nc",
        Some(feeder(&text.replace('\n', "\r\n"), 4096, 1)),
        2_000_000,
    );
    [file, stream]
}

fn messages(r: &RunResult) -> Vec<(String, bool)> {
    r.of("message")
        .iter()
        .map(|e| {
            (
                e["text"].as_str().unwrap().to_string(),
                e["save"].as_bool().unwrap(),
            )
        })
        .collect()
}

/// The run's one error: its code and the column its message names.
fn error_at(r: &RunResult) -> (u64, Option<u32>) {
    let e = r.of("error");
    assert_eq!(e.len(), 1, "{}", r.log);
    let msg = e[0]["msg"].as_str().unwrap();
    let col = msg
        .rsplit_once("(column ")
        .and_then(|(_, c)| c.trim_end_matches(')').parse().ok());
    (e[0]["code"].as_u64().unwrap(), col)
}

#[test]
fn msg_formats_its_values_as_printf_does_in_file_and_stream() {
    let rig = Rig::new();
    let text = "P1 = 2.5\nP2 = 7\nP3 = -0.125\n\
        #MSG [\"P1= %f\", P1]\n\
        #MSG [\"tool %d of %d: %5.2f mm\", P2, P2 + 1, P3 * 10]\n\
        #MSG SAVE EXCLUSIVE [\"%s%%\", P1 * 4]\n\
        #MSG INFO SYN HMI [\"RED,%D,BOLD\", 20]\n\
        #MSG SAVE CONTINUE [\"plain\"]\n\
        #MSG ACK PLC [no quotes %d]\n\
        M30\n";
    for r in both(&rig, text) {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        assert_eq!(
            messages(&r),
            [
                ("P1= 2.500000".to_string(), false),
                ("tool 7 of 8: -1.25 mm".to_string(), false),
                ("10%".to_string(), true),
                ("plain".to_string(), true),
                ("no quotes %d".to_string(), false),
                // SYN: when execution reaches its block, after the later blocks' decoding.
                ("RED,20,BOLD".to_string(), false),
            ]
        );
        assert_eq!(
            r.machine.channels()[0].status().message.as_deref(),
            Some("RED,20,BOLD")
        );
    }
    assert_eq!(check_program(text), []);
}

#[test]
fn msg_prints_string_variables_and_string_functions_with_s() {
    let rig = Rig::new();
    let text = "#VAR\n\
        V.L.NAME : STRING[20] = \"GRUNDPLATTE\"\n\
        V.P.PART : STRING[30]\n\
        #ENDVAR\n\
        V.P.PART = LEFT[V.L.NAME, 5] + \"-\" + RIGHT[V.L.NAME, 6]\n\
        #MSG [\"part %s (%d chars), %-8s|%.3s|\", V.P.PART, LEN[V.P.PART], \"ab\", V.L.NAME]\n\
        #MSG SAVE [\"%s at %d\", MID[\"How are you?\", 3, 5], FIND[V.L.NAME, \"PLATTE\"]]\n\
        M30\n";
    for r in both(&rig, text) {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        assert_eq!(
            messages(&r),
            [
                (
                    "part GRUND-PLATTE (12 chars), ab      |GRU|".to_string(),
                    false
                ),
                ("are at 6".to_string(), true),
            ]
        );
    }
    assert_eq!(check_program(text), []);
    // A string for %d is 900008, at the #MSG line.
    let text = "#VAR\nV.L.S : STRING[5] = \"x\"\n#ENDVAR\n#MSG [\"%d\", V.L.S]\nM30\n";
    for r in both(&rig, text) {
        assert_eq!(r.finish, Some(Finish::Error), "{}", r.log);
        assert_eq!(r.error_codes(), [u64::from(codes::EVAL_STRING_AS_NUMBER)]);
        assert_eq!(r.of("error")[0]["line"].as_u64(), Some(4));
    }
}

#[test]
fn msg_with_the_wrong_number_of_values_is_the_kernels_error_at_its_column() {
    let cases: [(&str, u32, usize); 6] = [
        // Fewer values than elements: 20721 at the closing bracket.
        ("#MSG [\"%d and %d\", 1]", codes::MSG_ARG_COUNT, 21),
        // More values than elements: 20721 at the first value too many.
        ("#MSG [\"%d\", 1, 2]", codes::MSG_ARG_COUNT, 16),
        ("#MSG [\"x=%d\", ]", codes::MSG_NO_VALUE, 15),
        ("#MSG [\"x=%q\", 1]", codes::MSG_UNKNOWN_FORMAT, 10),
        ("#MSG [\"x=%123f\", 1]", codes::MSG_UNKNOWN_FORMAT, 10),
        ("#MSG SAVE HMI [\"x\"]", codes::SYNTAX, 11),
    ];
    let rig = Rig::new();
    for (line, code, col) in cases {
        let text = format!("G1 X1 F1000\n{line}\nM30\n");
        let d = check_program(&text);
        assert_eq!(d.len(), 1, "{line}: {d:?}");
        assert_eq!((d[0].line, d[0].col, d[0].code), (2, col, code), "{line}");
        for r in both(&rig, &text) {
            assert_eq!(r.finish, Some(Finish::Error), "{line}");
            assert_eq!(error_at(&r), (u64::from(code), Some(col as u32)), "{line}");
            assert!(r.of("message").is_empty());
        }
    }
    let many = format!("#MSG [\"{}\"]", "%d".repeat(MAX_MSG_VALUES + 1));
    let e = parse_block(&many).unwrap_err();
    assert_eq!(e.code, codes::MSG_TOO_MANY_VALUES);
    assert!(e.message.contains(&MAX_MSG_VALUES.to_string()), "{e}");
}

#[test]
fn a_formatted_message_longer_than_the_bound_is_refused_not_allocated() {
    let rig = Rig::new();
    let elements = "%99.99f".repeat(MAX_MSG_VALUES);
    let values = ", P1".repeat(MAX_MSG_VALUES);
    let text = format!("P1 = 1000000\n#MSG [\"{elements}\"{values}]\nM30\n");
    assert_eq!(check_program(&text), [], "a run-time bound");
    for r in both(&rig, &text) {
        assert_eq!(r.finish, Some(Finish::Error));
        assert_eq!(error_at(&r).0, u64::from(codes::MSG_TOO_LONG));
        assert!(r.log.contains(&MAX_MSG_CHARS.to_string()), "{}", r.log);
    }
}

#[test]
fn msg_prints_back_as_text_that_parses_to_the_same_block() {
    for line in [
        "#MSG [\"P1= %f\", P1]",
        "#MSG SAVE EXCLUSIVE [\"a %d b %s\", [P1 + 2] * 3, V.L.X]",
        "#MSG INFO SYN_ACK EVENT_LOGGER [\"x\"]",
        "#MSG [free text]",
        "#MSG [\"a \"b\" c\"]",
    ] {
        let b = parse_block(line).unwrap();
        let printed = b.to_string();
        assert_eq!(parse_block(&printed).unwrap(), b, "{line} → {printed}");
    }
}

/// A rig whose channel list configures G800 and G805 (P-CHAN-00187) and their programs.
fn g800_rig() -> Rig {
    let rig = Rig::new();
    std::fs::write(
        rig.startup().with_file_name("channel1.lis"),
        "streaming_prog_file streaming.nc\n\
         g800_prog_file[0] g800.nc ( P-CHAN-00187\n\
         g800_prog_file[5] g805.nc\n\
         m_synch[200] MOS\nm_synch[201] MOS\n",
    )
    .unwrap();
    rig.program("g800.nc", "N5 G01 Z4 F6000\nN6 M17\n");
    rig.program("g805.nc", "N1 G01 X[@P1] Z[@P3] F6000\nN2 M17\n");
    rig
}

fn numbered_blocks(r: &RunResult) -> Vec<(String, u64)> {
    r.of("block")
        .iter()
        .map(|e| {
            (
                e["prog"].as_str().unwrap().to_string(),
                e["n"].as_u64().unwrap_or(0),
            )
        })
        .collect()
}

#[test]
fn g800_to_g819_call_their_configured_subroutine_with_its_parameters() {
    let rig = g800_rig();
    let text = "N10 G01 Y1 F6000\nN20 G805[-2.5, 3, 1.5]\nN30 G800\nN40 G805 [1, , 2] M30\n";
    assert_eq!(check_program(text), []);
    for (k, r) in both(&rig, text).iter().enumerate() {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        let main = if k == 0 { "t.nc" } else { "streaming.nc" };
        let want: Vec<(String, u64)> = [
            (main, 10),
            (main, 20),
            ("g805.nc", 1),
            ("g805.nc", 2),
            (main, 30),
            ("g800.nc", 5),
            ("g800.nc", 6),
            (main, 40),
            ("g805.nc", 1),
            ("g805.nc", 2),
        ]
        .iter()
        .map(|(p, n)| (p.to_string(), *n))
        .collect();
        assert_eq!(numbered_blocks(r), want, "{}", r.log);
        // The last call's @P1 and @P3 (the gap is @P2); Z of G800's program before it.
        assert_eq!(
            (r.position('X'), r.position('Y'), r.position('Z')),
            (1.0, 1.0, 2.0)
        );
        let end = r
            .events
            .iter()
            .position(|e| e["ev"] == "program_end")
            .unwrap();
        let last_block = r.events.iter().rposition(|e| e["ev"] == "block").unwrap();
        assert!(last_block < end, "the end waits for the subroutine");
    }
}

#[test]
fn an_unconfigured_g800_call_is_the_kernels_unknown_g_function_at_its_column() {
    let rig = g800_rig();
    for line in ["N20 G801", "N20 G801[1, 2]"] {
        let text = format!("N10 G01 X1 F6000\n{line}\nM30\n");
        // The channel list decides: the static check cannot know it.
        assert_eq!(check_program(&text), []);
        for r in both(&rig, &text) {
            assert_eq!(r.finish, Some(Finish::Error), "{line}");
            assert_eq!(
                error_at(&r),
                (u64::from(codes::UNKNOWN_G), Some(5)),
                "{line}"
            );
            assert!(r.log.contains("g800_prog_file[1]"), "{}", r.log);
        }
    }
}

#[test]
fn g800_parameters_are_checked_by_the_parser_in_check_and_run() {
    let rig = g800_rig();
    let many = format!("G805[{}]", vec!["1"; 51].join(", "));
    for (line, col) in [
        ("G805[1, 2", 10usize),
        ("G805[1 2]", 8),
        (many.as_str(), 156),
    ] {
        let text = format!("{line}\nM30\n");
        let d = check_program(&text);
        assert_eq!(d.len(), 1, "{line}: {d:?}");
        assert_eq!(
            (d[0].line, d[0].col, d[0].code),
            (1, col, codes::SYNTAX),
            "{line}"
        );
        for r in both(&rig, &text) {
            assert_eq!(error_at(&r), (u64::from(codes::SYNTAX), Some(col as u32)));
        }
    }
    for line in [
        "G805[-27.12, 28.955, 2.87]",
        "G800[, 2, ]",
        "G819[]",
        "G801[1, , ]",
    ] {
        let b = parse_block(line).unwrap();
        assert_eq!(parse_block(&b.to_string()).unwrap(), b, "{line}");
    }
}

#[test]
fn tool_and_channel_commands_and_weightings_are_inert_blocks_that_change_no_path() {
    let rig = Rig::new();
    let text = "N10 G01 X1 F6000\n\
        N20 #TOOL PREP [2]\n\
        N30 #TOOL DATA [V.G.T_AKT]\n\
        N40 #TOOL LIFE READ [2, 1]\n\
        N50 #CHANNEL INIT [CMDPOS]\n\
        N60 G129=70\n\
        N70 G131 = 50\n\
        N80 G130 X70 Y75\n\
        N90 G231=80\n\
        N100 G233=60\n\
        N110 G129=70 Y2\n\
        N120 M30\n";
    assert_eq!(check_program(text), []);
    for r in both(&rig, text) {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        let texts = r.block_texts();
        assert_eq!(texts.len(), 12, "{texts:?}");
        assert!(texts[1].contains("#TOOL PREP [2]"), "{texts:?}");
        assert!(texts[4].contains("#CHANNEL INIT [CMDPOS]"), "{texts:?}");
        // G130's axis words are weights: X stays at 1, Y is moved only by N110.
        assert_eq!((r.position('X'), r.position('Y')), (1.0, 2.0));
    }
    // The other forms of the keywords stay refused by name, the axis-specific G00 ones too.
    for line in ["#TOOL ORI [1]", "#CHANNEL SET [X]", "G230 X50", "G232 X50"] {
        let e = parse_block(line).unwrap_err();
        assert_eq!((e.code, e.col), (codes::UNSUPPORTED, 1), "{line}");
    }
}

#[test]
fn contour_mode_on_and_off_are_g261_and_g260_with_the_deviation() {
    let rig = Rig::new();
    let square = "G01 X20 F3000\nY20\nX0\nY0\n";
    let switched =
        format!("#CONTOUR MODE ON [DEV PATH_DEV=0.08]\n{square}#CONTOUR MODE OFF\n{square}M30\n");
    let by_g = format!("#CONTOUR MODE [DEV PATH_DEV=0.08]\nG261\n{square}G260\n{square}M30\n");
    let sharp = format!("{square}{square}M30\n");
    assert_eq!(check_program(&switched), []);
    let [a, a_stream] = both(&rig, &switched);
    let [b, _] = both(&rig, &by_g);
    let [c, _] = both(&rig, &sharp);
    for r in [&a, &a_stream, &b, &c] {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    }
    assert_eq!(a.ticks, b.ticks, "ON/OFF contour as G261/G260 do");
    assert_eq!(a_stream.ticks, a.ticks);
    assert!(
        a.ticks < c.ticks,
        "{} contoured, {} sharp",
        a.ticks,
        c.ticks
    );
    // Only the first square is blended: with the second one contoured too it would be shorter.
    let [d, _] = both(
        &rig,
        &format!("#CONTOUR MODE ON [DEV PATH_DEV=0.08]\n{square}{square}M30\n"),
    );
    assert!(
        d.ticks < a.ticks,
        "{} both contoured, {} first only",
        d.ticks,
        a.ticks
    );
    for line in ["#CONTOUR MODE ON [DEV PATH_DEV=0.08]", "#CONTOUR MODE OFF"] {
        let b = parse_block(line).unwrap();
        assert_eq!(b.to_string(), line);
    }
}

#[test]
fn a_local_subroutine_without_m17_ends_at_the_next_program_head() {
    let rig = Rig::new();
    let subs = "%L SUB1\nN1 G01 X5 F6000\n%L SUB2\nN2 G01 Y5 F6000\n";
    let called = format!("{subs}%main\nN10 LL SUB1\nN20 LL SUB2\nN30 M30\n");
    assert_eq!(check_program(&called), []);
    rig.program("t.nc", &called);
    let r = rig.run("t.nc", None, 2_000_000);
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let n: Vec<u64> = numbered_blocks(&r).iter().map(|(_, n)| *n).collect();
    assert_eq!(n, [10, 1, 20, 2, 30]);
    assert_eq!((r.position('X'), r.position('Y')), (5.0, 5.0));
    // Not called, the sections are passed over up to the main program, in a file and streamed.
    let passed = format!("{subs}%main\nN10 G01 Z1 F6000\nN20 M30\n");
    for r in both(&rig, &passed) {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        let n: Vec<u64> = numbered_blocks(&r).iter().map(|(_, n)| *n).collect();
        assert_eq!(n, [10, 20]);
        assert_eq!((r.position('X'), r.position('Z')), (0.0, 1.0));
    }
}

#[test]
fn a_printer_post_processor_program_runs_to_m30_with_its_own_g80x_subroutines() {
    // In the style of a bioprinter's post-processor for a TwinCAT CNC: a head with blanks
    // and a comment, M functions with values (pressure on and off), a layer start as a G805
    // call continued over two lines, contouring switched on with its deviation, a message
    // with a value, a flush before the pressure goes off, and a park call G800.
    let rig = g800_rig();
    let text = "% Bioprinter job 42 (generated)\n\
        N10 G17 G90 G71\n\
        N20 #CONTOUR MODE ON [DEV PATH_DEV=0.08]\n\
        N30 M200=1200\n\
        N40 G805[0, \\\n     0, 1.5]\n\
        N50 #MSG [\"layer %d of %d\", 1, 1]\n\
        N60 G01 X20 Y0 F3000\n\
        N70 X20 Y20\n\
        N80 X0 Y20\n\
        N90 X0 Y0\n\
        N100 #FLUSH WAIT\n\
        N110 M201=0\n\
        N120 G800\n\
        N130 #CONTOUR MODE OFF\n\
        N140 M30\n";
    assert_eq!(check_program(text), []);
    for (k, r) in both(&rig, text).iter().enumerate() {
        assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
        assert!(r.error_codes().is_empty(), "{}", r.log);
        let main = if k == 0 { "t.nc" } else { "streaming.nc" };
        let calls: Vec<(String, u64)> = numbered_blocks(r)
            .into_iter()
            .filter(|(p, _)| p != main)
            .collect();
        let want: Vec<(String, u64)> = [
            ("g805.nc", 1),
            ("g805.nc", 2),
            ("g800.nc", 5),
            ("g800.nc", 6),
        ]
        .iter()
        .map(|(p, n)| (p.to_string(), *n))
        .collect();
        assert_eq!(calls, want, "{}", r.log);
        let m_values: Vec<(u64, Option<i64>)> = r
            .of("techno_output")
            .iter()
            .map(|e| (e["number"].as_u64().unwrap(), e["value"].as_i64()))
            .collect();
        assert_eq!(m_values, [(200, Some(1200)), (201, None)], "{}", r.log);
        assert_eq!(messages(r), [("layer 1 of 1".to_string(), false)]);
        // The square closed at the origin at the layer height, then G800 lifted Z to 4.
        assert_eq!(
            (r.position('X'), r.position('Y'), r.position('Z')),
            (0.0, 0.0, 4.0)
        );
    }
}
