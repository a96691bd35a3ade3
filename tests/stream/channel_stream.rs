//! The channel with its stream interface, driven through the library in virtual time.

use crate::support as common;

use common::{crlf, feeder, tick0, Rig};
use ncchannel::channel::{Finish, State};
use ncchannel::machine::Op;
use ncchannel::Feeder;

#[test]
fn stream_as_main_program_runs_every_block_and_ends() {
    let rig = Rig::new();
    let r = rig.run(
        "streaming.nc",
        Some(feeder(
            "N10 G01 X10 F6000\nN20 Y10\nN30 P1=5\nM30\n",
            992,
            1,
        )),
        100_000,
    );
    assert_eq!(r.finish, Some(Finish::Ended));
    assert_eq!(
        r.block_texts(),
        ["N10 G01 X10 F6000", "N20 Y10", "N30 P1=5", "M30"]
    );
    let start = r.of("program_start");
    assert_eq!(start[0]["prog"], "streaming.nc");
    assert_eq!(start[0]["stream"], true);
    let end = r.of("program_end");
    assert_eq!(end[0]["end"], "M30");
    let pos = r.machine.channels()[0].report().position;
    assert!((pos[0] - 10.0).abs() < 1e-9 && (pos[1] - 10.0).abs() < 1e-9);
}

#[test]
fn activation_by_global_call_from_a_file_program_and_back() {
    // Seed 003 §2.2: N10–N40 in a file, then the stream, then back to the file.
    let rig = Rig::new();
    rig.program(
        "main.nc",
        "N10 G01 X200 F1000\nN20 X240 Y100\nN30 X200 Y0\nN40 L streaming.nc\nN50 G0 X0 Y0\nM30\n",
    );
    let r = rig.run(
        "main.nc",
        Some(feeder("N100 G1 X10 F6000\nN110 Y10\nM17\n", 992, 1)),
        1_000_000,
    );
    assert_eq!(r.finish, Some(Finish::Ended), "{}", r.log);
    let blocks: Vec<(String, String)> = r
        .of("block")
        .iter()
        .map(|e| {
            (
                e["prog"].as_str().unwrap().to_string(),
                e["text"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let expect = [
        ("main.nc", "N10 G01 X200 F1000"),
        ("main.nc", "N20 X240 Y100"),
        ("main.nc", "N30 X200 Y0"),
        ("main.nc", "N40 L streaming.nc"),
        ("streaming.nc", "N100 G1 X10 F6000"),
        ("streaming.nc", "N110 Y10"),
        ("streaming.nc", "M17"),
        ("main.nc", "N50 G0 X0 Y0"),
        ("main.nc", "M30"),
    ];
    let expect: Vec<(String, String)> = expect
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(blocks, expect);
}

#[test]
fn packets_written_before_the_read_merge_into_one_segment() {
    let rig = Rig::new();
    let (mut channel, period) = rig.channel();
    let t = tick0(period);
    let c = &mut channel;
    // Data written while no streaming program runs is kept for the next one.
    assert_eq!(common::write(c, &t, &crlf("N1 P1=1\n")), common::WRITTEN);
    assert_eq!(
        common::write(c, &t, &crlf("N2 P2=2\nN3 P3=3\n")),
        common::WRITTEN
    );
    assert_eq!(c.report().stream_fill.0, 9 + 18);
    common::start(c, &t, "streaming.nc");
    c.step(&t);
    let ev = common::channel_events(c);
    let segs = common::of(&ev, "segment");
    assert_eq!(segs.len(), 1);
    assert_eq!(segs[0]["bytes"], 27);
}

#[test]
fn m30_mid_segment_discards_the_rest_of_the_segment_but_not_later_data() {
    let rig = Rig::new();
    let (mut channel, period) = rig.channel();
    let t = tick0(period);
    let c = &mut channel;
    assert_eq!(
        common::write(c, &t, &crlf("N1 P1=1\nM30\nN2 P2=2\n")),
        common::WRITTEN
    );
    common::start(c, &t, "streaming.nc");
    c.step(&t);
    // Written after the segment was read: stays in the buffer for the next program.
    assert_eq!(common::write(c, &t, &crlf("N9 P9=9\n")), common::WRITTEN);
    for _ in 0..5 {
        c.step(&t);
    }
    assert_eq!(c.status().state, State::Ready);
    let ev = common::channel_events(c);
    let discard = common::of(&ev, "discard");
    assert_eq!(discard.len(), 1);
    assert_eq!(discard[0]["bytes"], 9, "'N2 P2=2\\r\\n' dropped");
    let texts = common::block_texts(&ev);
    assert_eq!(texts, ["N1 P1=1", "M30"]);
    assert_eq!(c.report().stream_fill.0, 9);
    // The next start runs it.
    common::start(c, &t, "streaming.nc");
    assert_eq!(common::write(c, &t, &crlf("M30\n")), common::WRITTEN);
    for _ in 0..5 {
        c.step(&t);
    }
    let ev = common::channel_events(c);
    let texts = common::block_texts(&ev);
    assert_eq!(&texts[2..], ["N9 P9=9", "M30"]);
}

/// A ~1 MB program: short moves and parameter blocks, every line different.
fn big_program() -> String {
    let mut s = String::from("N1 G01 F60000\nN2 P1=0\n");
    let mut i = 0u64;
    while s.len() < 1_000_000 {
        i += 1;
        if i.is_multiple_of(3) {
            s.push_str(&format!("N{i} P{} = [P1 + {i}]\n", 2 + i % 50));
        } else {
            s.push_str(&format!(
                "N{i} X{:.3} Y{:.3}\n",
                (i % 200) as f64 * 0.01,
                (i % 77) as f64 * 0.01
            ));
        }
    }
    s.push_str("M30\n");
    s
}

#[test]
fn a_megabyte_streamed_in_992_byte_packets_runs_every_block_once_in_order() {
    let rig = Rig::new();
    let text = big_program();
    let r = rig.run(
        "streaming.nc",
        Some(Feeder::new(text.clone().into_bytes(), 992, 1, false).unwrap()),
        10_000_000,
    );
    assert_eq!(r.finish, Some(Finish::Ended), "{:?}", r.of("error"));
    let expect: Vec<&str> = text.lines().collect();
    assert_eq!(r.block_texts(), expect);
    // A writer faster than the machine fills the buffer and hears 11012, then retries.
    let rejected = r.of("write").iter().filter(|e| e["ok"] == false).count();
    assert!(rejected > 0, "the feeder outran the channel at least once");
    assert!(r.of("warning").iter().all(|w| w["code"] == 11012));
    assert_eq!(r.of("warning").len(), rejected);
    let accepted: u64 = r
        .of("write")
        .iter()
        .filter(|e| e["ok"] == true)
        .map(|e| e["bytes"].as_u64().unwrap())
        .sum();
    assert_eq!(accepted as usize, crlf(&text).len());
}

#[test]
fn a_line_without_cr_lf_raises_21476_and_stops_the_channel() {
    let rig = Rig::new();
    let f = Feeder::new(b"N1 P1=1\nN2 P2=2\n".to_vec(), 992, 1, true).unwrap();
    let r = rig.run("streaming.nc", Some(f), 1000);
    assert_eq!(r.finish, Some(Finish::Error));
    assert_eq!(r.error_codes(), [21476]);
    assert_eq!(r.machine.channels()[0].status().state, State::Error);
    // The kernel's text once, then where in the packet: no second number, no second text.
    let msg = r.of("error")[0]["msg"].as_str().unwrap_or("").to_string();
    assert_eq!(
        msg,
        "Streaming data does not contain a correct line end marker (packet byte 7)"
    );
}

#[test]
fn a_starved_stream_interrupts_and_resumes() {
    let rig = Rig::new();
    // `#FLUSH CONTINUE` releases the held block; a form feed ends the packet and pauses the
    // feeder 500 ticks, longer than the move takes.
    let text = "N1 G01 X10 F6000\n#FLUSH CONTINUE\n\x0c 500\nN2 X20\nM30\n";
    let r = rig.run("streaming.nc", Some(feeder(text, 992, 1)), 100_000);
    assert_eq!(r.finish, Some(Finish::Ended));
    let kinds: Vec<&str> = r
        .events
        .iter()
        .filter(|e| ["interrupt", "resume", "block"].contains(&e["ev"].as_str().unwrap()))
        .map(|e| e["ev"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        ["block", "block", "interrupt", "resume", "block", "block"]
    );
    assert_eq!(r.machine.channels()[0].report().stats.interrupts, 1);
}

#[test]
fn a_fast_feeder_gives_no_interrupt() {
    let rig = Rig::new();
    let text: String = (1..200)
        .map(|i| format!("N{i} G01 X{i} F6000\n"))
        .collect::<String>()
        + "M30\n";
    let r = rig.run("streaming.nc", Some(feeder(&text, 992, 1)), 1_000_000);
    assert_eq!(r.finish, Some(Finish::Ended));
    assert!(r.of("interrupt").is_empty());
}

#[test]
fn reset_empties_buffer_and_state() {
    let rig = Rig::new();
    let (mut channel, period) = rig.channel();
    let t = tick0(period);
    let c = &mut channel;
    assert_eq!(
        common::write(c, &t, &crlf("N1 G01 X100 F600\nN2 X0\n")),
        common::WRITTEN
    );
    common::start(c, &t, "streaming.nc");
    c.step(&t);
    assert_eq!(common::write(c, &t, &crlf("N3 X5\n")), common::WRITTEN);
    assert!(c.report().reads_stream);
    c.apply(&t, Op::Reset);
    assert_eq!(c.status().state, State::Ready);
    assert_eq!(c.report().stream_fill, (0, 4094));
    assert!(!c.report().reads_stream);
    assert_eq!(c.status().block_counter, 0);
    assert!(c.report().last_error.is_none());
}

#[test]
fn two_virtual_runs_give_identical_event_logs() {
    let rig = Rig::new();
    let text: String = (1..300)
        .map(|i| format!("N{i} G01 X{} Y{} F3000\n", i % 17, i % 5))
        .collect::<String>()
        + "M30\n";
    let a = rig.run("streaming.nc", Some(feeder(&text, 200, 3)), 1_000_000);
    let b = rig.run("streaming.nc", Some(feeder(&text, 200, 3)), 1_000_000);
    assert_eq!(a.finish, Some(Finish::Ended));
    assert!(!a.log.is_empty());
    assert_eq!(a.log, b.log);
}

#[test]
fn unknown_main_program_is_20368_and_unknown_subroutine_20369() {
    let rig = Rig::new();
    let r = rig.run("nothere.nc", None, 100);
    assert_eq!(r.error_codes(), [20368]);
    rig.program("m.nc", "N1 L nosub.nc\nM30\n");
    let r = rig.run("m.nc", None, 100);
    assert_eq!(r.error_codes(), [20369]);
}

#[test]
fn the_error_list_is_bounded_and_counts_the_rest() {
    let rig = Rig::new();
    let (mut channel, period) = rig.channel();
    let t = tick0(period);
    let c = &mut channel;
    for _ in 0..1000 {
        let _ = c.apply(&t, Op::WriteStream(b"N1 X1\n".as_slice().into()));
        c.apply(&t, Op::Reset);
    }
    assert_eq!(c.report().stats.errors, 1000);
    assert_eq!(
        c.report().errors.len(),
        ncchannel::channel::MAX_LISTED_ERRORS
    );
    assert!(c.report().errors.iter().all(|e| e.code == 21476));
}
