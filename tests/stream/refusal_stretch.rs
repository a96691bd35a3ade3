//! A writer retrying a full stream buffer every 250 µs, as the interface prescribes (ADS
//! 0x708, warning 11012), costs the event log a constant number of lines per stretch of
//! refusals, and the stretch's event counts every refusal.

use std::sync::Arc;
use std::time::Duration;

use crate::support as common;

use common::{channel_events, Rig};
use ncchannel::machine::Op;
use ncchannel::runtime::Tick;

/// Retries per 1 ms tick at one retry every 250 µs.
const RETRIES_PER_TICK: u64 = 4;

fn tick(index: u64, period: Duration) -> Tick {
    Tick {
        index,
        period,
        time: period * u32::try_from(index).expect("small tick index"),
        clock: ncchannel::runtime::Clock::Virtual,
    }
}

/// 987 bytes of whole lines: the buffer (4094 bytes) takes four, then refuses.
fn packet() -> Arc<[u8]> {
    "N1 X1\r\n".repeat(141).into_bytes().into()
}

#[test]
fn a_retry_storm_is_one_stretch_of_three_lines_with_the_right_count() {
    let rig = Rig::new();
    let (mut c, period) = rig.channel();
    let mut t = 0;
    // Fill the buffer (the channel does not run, so nothing takes the data out).
    let mut accepted = 0;
    while matches!(
        c.apply(&tick(t, period), Op::WriteStream(packet())),
        ncchannel::machine::Reply::Stream(Ok(()))
    ) {
        accepted += 1;
    }
    assert_eq!(accepted, 4);
    let first_refusal_tick = t;
    // Ten seconds of retries: 40,000 refusals besides the first.
    let mut refusals = 1u64;
    for _ in 0..10_000 {
        t += 1;
        c.step(&tick(t, period));
        for _ in 0..RETRIES_PER_TICK {
            let r = c.apply(&tick(t, period), Op::WriteStream(packet()));
            assert!(
                matches!(r, ncchannel::machine::Reply::Stream(Err(_))),
                "{r:?}"
            );
            refusals += 1;
        }
    }
    // Room for a short packet: the writer gets through and the stretch is over.
    t += 1;
    let short: Arc<[u8]> = b"N2 X2\r\n".as_slice().into();
    let r = c.apply(&tick(t, period), Op::WriteStream(short));
    assert!(
        matches!(r, ncchannel::machine::Reply::Stream(Ok(()))),
        "{r:?}"
    );

    let events = channel_events(&mut c);
    let refused_writes: Vec<_> = events
        .iter()
        .filter(|e| e["ev"] == "write" && e["ok"] == false)
        .collect();
    let warnings = common::of(&events, "warning");
    let stretches = common::of(&events, "writes_refused");
    assert_eq!(refused_writes.len(), 1, "the first refusal only");
    assert_eq!(refused_writes[0]["code"], 11012);
    assert_eq!(warnings.len(), 1, "the first refusal only");
    assert_eq!(stretches.len(), 1, "{stretches:?}");
    assert_eq!(stretches[0]["count"], refusals, "every refusal counted");
    assert_eq!(stretches[0]["code"], 11012);
    assert_eq!(stretches[0]["first_tick"], first_refusal_tick);
    assert_eq!(
        stretches[0]["tick"], t,
        "closed by the write that got through"
    );
    // 4 accepted, the stretch's 3 lines, the accepted short write.
    assert_eq!(events.len(), 8, "{events:?}");
    // The channel's own count of warnings still counts every refusal.
    assert_eq!(c.report().stats.warnings, refusals);
}
