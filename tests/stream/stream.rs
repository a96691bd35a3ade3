//! The stream buffer as the channel and its clients rely on it: 4094/992 limits, whole-or-
//! nothing writes, CR LF checking, one segment per read, reset.

use ncchannel::{
    StreamBuffer, StreamWriteError, MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_SIZE,
};
use proptest::prelude::*;

/// A packet of exactly `len` bytes made of CR LF lines.
fn packet(len: usize, fill: u8) -> Vec<u8> {
    assert!(len >= 2);
    let mut p = vec![fill; len - 2];
    p.extend_from_slice(b"\r\n");
    p
}

#[test]
fn limits_are_the_documented_ones() {
    assert_eq!(MAX_PROGRAM_STREAM_SIZE, 4094);
    assert_eq!(MAX_PROGRAM_STREAM_INPUT_SIZE, 992);
}

#[test]
fn empty_and_oversized_writes_are_writer_errors_that_change_nothing() {
    let mut b = StreamBuffer::new();
    b.write(b"N1\r\n").unwrap();
    assert_eq!(b.write(b""), Err(StreamWriteError::Empty));
    assert_eq!(
        b.write(&packet(993, b'X')),
        Err(StreamWriteError::TooLarge { len: 993 })
    );
    assert_eq!(StreamWriteError::Empty.isg_code(), None);
    assert_eq!(StreamWriteError::TooLarge { len: 993 }.isg_code(), None);
    assert_eq!(b.used(), 4);
    // 992 exactly is fine.
    b.write(&packet(992, b'Y')).unwrap();
    assert_eq!(b.used(), 996);
    assert_eq!(b.counters().writes_invalid, 2);
    assert_eq!(b.counters().writes_ok, 2);
}

#[test]
fn bad_line_ends_are_21476_and_change_nothing() {
    let mut b = StreamBuffer::new();
    for (bad, offset) in [
        (&b"N10 X1\nN20\r\n"[..], 6),
        (&b"N10 X1\rN20\r\n"[..], 6),
        (&b"N10 X1\r\nN20"[..], 11),
        (&b"N10 X1"[..], 6),
        (&b"\n"[..], 0),
    ] {
        let e = b.write(bad).unwrap_err();
        assert_eq!(e, StreamWriteError::NoLineEnd { offset }, "{bad:?}");
        assert_eq!(e.isg_code(), Some(21476));
        assert!(e.to_string().contains("21476"));
        assert_eq!(b.used(), 0);
    }
}

#[test]
fn a_write_that_does_not_fit_is_11012_and_fits_after_a_read() {
    let mut b = StreamBuffer::new();
    for _ in 0..4 {
        b.write(&packet(992, b'A')).unwrap();
    }
    assert_eq!(b.free(), 4094 - 3968);
    let big = packet(200, b'B');
    let e = b.write(&big).unwrap_err();
    assert_eq!(e, StreamWriteError::Full { free: 126 });
    assert_eq!(e.isg_code(), Some(11012));
    assert_eq!(b.used(), 3968);
    // Exactly filling is allowed.
    b.write(&packet(126, b'C')).unwrap();
    assert_eq!(b.free(), 0);
    assert_eq!(b.counters().writes_full, 1);
    let mut seg = Vec::new();
    assert_eq!(b.take_segment(&mut seg), 4094);
    b.write(&big).unwrap();
}

#[test]
fn malformed_packet_reports_21476_even_when_full() {
    let mut b = StreamBuffer::new();
    for _ in 0..4 {
        b.write(&packet(992, b'A')).unwrap();
    }
    assert!(matches!(
        b.write(&[b'N'; 300]),
        Err(StreamWriteError::NoLineEnd { .. })
    ));
}

#[test]
fn packets_merge_into_one_segment_in_write_order() {
    let mut b = StreamBuffer::new();
    b.write(b"N1 G01 X1\r\n").unwrap();
    b.write(b"N2 X2\r\nN3 X3\r\n").unwrap();
    b.write(b"N4 M30\r\n").unwrap();
    let mut seg = Vec::with_capacity(4094);
    let cap = seg.capacity();
    let n = b.take_segment(&mut seg);
    assert_eq!(seg, b"N1 G01 X1\r\nN2 X2\r\nN3 X3\r\nN4 M30\r\n");
    assert_eq!(n, seg.len());
    assert_eq!(seg.capacity(), cap, "take reuses the caller's allocation");
    assert!(b.is_empty());
    assert_eq!(b.counters().segments, 1);
    assert_eq!(b.counters().bytes_taken, n as u64);
}

#[test]
fn clear_drops_data_and_reports_how_much() {
    let mut b = StreamBuffer::new();
    b.write(b"N1 X1\r\n").unwrap();
    assert_eq!(b.clear(), 7);
    assert_eq!(b.used(), 0);
    assert_eq!(b.free(), 4094);
    let mut seg = vec![1, 2, 3];
    assert_eq!(b.take_segment(&mut seg), 0);
    assert!(seg.is_empty());
}

proptest! {
    /// Random packets (valid, malformed, too big, or not fitting) interleaved with reads:
    /// every accepted byte comes out exactly once, in order, and nothing else does.
    #[test]
    fn every_accepted_byte_comes_out_once_in_order(
        ops in proptest::collection::vec(
            prop_oneof![
                3 => (1usize..12, 0usize..120).prop_map(|(lines, len)| Some((lines, len))),
                1 => Just(None),
            ],
            1..200,
        ),
        bad in proptest::collection::vec(any::<bool>(), 200),
    ) {
        let mut b = StreamBuffer::new();
        let mut expected = Vec::new();
        let mut got = Vec::new();
        let mut seg = Vec::new();
        let mut counter = 0u32;
        for (i, op) in ops.iter().enumerate() {
            match op {
                Some((lines, len)) => {
                    let mut p = Vec::new();
                    for _ in 0..*lines {
                        counter += 1;
                        let body = format!("N{counter} {}", "X".repeat(*len));
                        p.extend_from_slice(body.as_bytes());
                        p.extend_from_slice(b"\r\n");
                    }
                    if bad[i] {
                        p.pop(); // drop the final LF
                    }
                    let before = b.used();
                    match b.write(&p) {
                        Ok(()) => {
                            prop_assert!(!bad[i]);
                            expected.extend_from_slice(&p);
                        }
                        Err(e) => {
                            prop_assert_eq!(b.used(), before);
                            match e {
                                StreamWriteError::Full { free } => prop_assert!(p.len() > free),
                                StreamWriteError::TooLarge { len } => prop_assert!(len > 992),
                                StreamWriteError::NoLineEnd { .. } => prop_assert!(bad[i]),
                                StreamWriteError::Empty => prop_assert!(false),
                            }
                        }
                    }
                }
                None => {
                    let n = b.take_segment(&mut seg);
                    prop_assert_eq!(n, seg.len());
                    got.extend_from_slice(&seg);
                }
            }
            prop_assert!(b.used() <= MAX_PROGRAM_STREAM_SIZE);
        }
        b.take_segment(&mut seg);
        got.extend_from_slice(&seg);
        prop_assert_eq!(got, expected);
    }
}
