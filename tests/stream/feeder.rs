//! The built-in feeder: whole lines, CR LF, packet limits, form-feed pauses, retries, raw.

use ncchannel::ads::client::LineTooLong;
use ncchannel::{Feeder, FeederError};

/// Drive the feeder for `ticks` ticks accepting every write; (tick, packet) per write.
fn run(f: &mut Feeder, ticks: u64) -> Vec<(u64, Vec<u8>)> {
    let mut out = Vec::new();
    for t in 0..ticks {
        if let Some(p) = f.poll(t) {
            out.push((t, p.to_vec()));
            f.result(true);
        }
    }
    out
}

#[test]
fn lines_are_normalised_to_cr_lf_and_packed_whole() {
    let text = b"N10 X1\nN20 X2\r\nN30 X3\nN40 M30".to_vec();
    let mut f = Feeder::new(text, 17, 1, false).unwrap();
    let w = run(&mut f, 10);
    let packets: Vec<&[u8]> = w.iter().map(|(_, p)| p.as_slice()).collect();
    assert_eq!(
        packets,
        vec![&b"N10 X1\r\nN20 X2\r\n"[..], &b"N30 X3\r\nN40 M30\r\n"[..]]
    );
    assert_eq!(w[0].0, 0);
    assert_eq!(w[1].0, 1);
    assert!(f.done());
    assert_eq!(f.counters().writes_ok, 2);
    assert_eq!(f.counters().bytes, 33);
}

#[test]
fn a_text_already_in_cr_lf_lines_is_packed_as_an_lf_text_is() {
    // The CR LF text is kept as it is (not copied); its packets must be those of the same
    // lines written with LF.
    let lf = b"N10 X1\nN20 X2\nN30 X3\nN40 M30\n".to_vec();
    let crlf = b"N10 X1\r\nN20 X2\r\nN30 X3\r\nN40 M30\r\n".to_vec();
    let mut a = Feeder::new(lf, 17, 1, false).unwrap();
    let mut b = Feeder::new(crlf, 17, 1, false).unwrap();
    assert_eq!(a.packets(), 2);
    assert_eq!(a.total_bytes(), b.total_bytes());
    assert_eq!(run(&mut a, 10), run(&mut b, 10));
    let long = b"N10 X1\r\nN20 X2 Y3 Z4 A5 B6 C7\r\n".to_vec();
    assert!(matches!(
        Feeder::new(long, 17, 1, false),
        Err(FeederError::LineTooLong(LineTooLong { line: 2, .. }))
    ));
}

#[test]
fn packets_never_exceed_the_maximum_and_never_split_a_line() {
    let mut text = String::new();
    for i in 0..500 {
        text.push_str(&format!("N{i} G01 X{} Y{}\n", i * 3, i % 17));
    }
    let mut f = Feeder::new(text.clone().into_bytes(), 100, 1, false).unwrap();
    let w = run(&mut f, 10_000);
    let mut all = Vec::new();
    for (i, (_, p)) in w.iter().enumerate() {
        assert!(p.len() <= 100);
        if i + 1 < w.len() {
            assert!(p.len() > 100 - 24, "packets are filled, not one line each");
        }
        assert!(p.ends_with(b"\r\n"));
        all.extend_from_slice(p);
    }
    assert_eq!(all, text.replace('\n', "\r\n").into_bytes());
}

#[test]
fn a_line_longer_than_a_packet_is_an_error_up_front() {
    let e = Feeder::new(b"N1\nN2 XXXXXXXXXXXX\n".to_vec(), 10, 1, false).unwrap_err();
    assert_eq!(
        e,
        FeederError::LineTooLong(LineTooLong {
            line: 2,
            bytes: 17,
            max: 10
        })
    );
    assert_eq!(
        Feeder::new(b"N1\n".to_vec(), 0, 1, false).unwrap_err(),
        FeederError::ZeroPacket
    );
}

#[test]
fn form_feed_ends_the_packet_and_pauses() {
    let text = b"N1\nN2\n\x0c 5\nN3\n\x0c\nN4\n".to_vec();
    let mut f = Feeder::new(text, 992, 1, false).unwrap();
    let w = run(&mut f, 50);
    assert_eq!(
        w,
        vec![
            (0, b"N1\r\nN2\r\n".to_vec()),
            // accepted at 0, next attempt at 0 + 1 + 5: ticks 1..=5 are the pause.
            (6, b"N3\r\n".to_vec()),
            // a bare form feed only cuts the packet.
            (7, b"N4\r\n".to_vec()),
        ]
    );
    assert_eq!(
        Feeder::new(b"N1\n\x0c abc\n".to_vec(), 992, 1, false).unwrap_err(),
        FeederError::BadPause { line: 2 }
    );
}

#[test]
fn a_leading_pause_delays_the_first_write() {
    let mut f = Feeder::new(b"\x0c3\nN1\n".to_vec(), 992, 1, false).unwrap();
    let w = run(&mut f, 10);
    assert_eq!(w, vec![(3, b"N1\r\n".to_vec())]);
}

#[test]
fn every_spaces_attempts_and_a_rejected_packet_is_retried() {
    let mut f = Feeder::new(b"N1\nN2\n".to_vec(), 4, 3, false).unwrap();
    assert_eq!(f.poll(0), Some(&b"N1\r\n"[..]));
    f.result(false);
    assert_eq!(f.poll(1), None);
    assert_eq!(f.poll(2), None);
    assert_eq!(f.poll(3), Some(&b"N1\r\n"[..]));
    f.result(true);
    assert_eq!(f.poll(5), None);
    assert_eq!(f.poll(6), Some(&b"N2\r\n"[..]));
    assert!(!f.done());
    f.result(true);
    assert!(f.done());
    assert_eq!(f.poll(100), None);
    assert_eq!(f.counters().writes_ok, 2);
    assert_eq!(f.counters().writes_rejected, 1);
}

#[test]
fn raw_mode_sends_bytes_as_they_are() {
    let text = b"N1 X1\nN2\rN3\x0c 9\n".to_vec();
    let mut f = Feeder::new(text.clone(), 4, 1, true).unwrap();
    let w = run(&mut f, 20);
    let packets: Vec<Vec<u8>> = w.into_iter().map(|(_, p)| p).collect();
    assert!(packets.iter().all(|p| p.len() <= 4));
    assert_eq!(packets.concat(), text);
    assert_eq!(packets.len(), 4);
}

#[test]
fn rewind_starts_over() {
    let mut f = Feeder::new(b"N1\n".to_vec(), 992, 1, false).unwrap();
    assert_eq!(run(&mut f, 3).len(), 1);
    assert!(f.done());
    f.rewind();
    assert!(!f.done());
    assert_eq!(f.poll(10), Some(&b"N1\r\n"[..]));
}
