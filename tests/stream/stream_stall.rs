//! `ncchannel stream` against a healthy program whose long move keeps the stream buffer full
//! for longer than `--stall-secs`: not a stall (the timer counts only while no program runs),
//! so it finishes with exit 0.

use crate::support as common;

use std::process::Command;

use common::{Rig, Served};

#[test]
fn a_long_move_that_keeps_the_buffer_full_is_not_a_stall() {
    let rig = Rig::new();
    // A 3 s move (30 mm at 600 mm/min), then more than a buffer's worth of lines behind it.
    let mut text = String::from("N1 G01 X30 F600\n");
    for i in 2..600 {
        text.push_str(&format!("N{i} P1={i}\n"));
    }
    text.push_str("M30\n");
    let file = rig.dir.path().join("long_move.nc");
    std::fs::write(&file, text).unwrap();
    let served = Served::start(&rig);
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["stream", "--start", "--stall-secs", "1", "--target"])
        .arg(served.server.local_addr().to_string())
        .arg(&file)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Every line is in the channel; the 3 s move and the lines behind it run to the end.
    served.wait_blocks(600, std::time::Duration::from_secs(60));
    let (_, events) = served.finish();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("rejected busy"), "{stderr}");
    assert_eq!(common::block_texts(&events).len(), 600, "every line ran");
}
