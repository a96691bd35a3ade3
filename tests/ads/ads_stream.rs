//! `ncchannel stream` and the client library behind it, against a server over real channels
//! (tests/ads_common): everything sent is executed once, in order, through a full buffer.

use ncchannel::vocab::mode::State;

use std::process::Command;
use std::time::Duration;

use crate::support::ads::*;
use ncchannel::ads::client::{self, AdsClient, StreamError, StreamOptions};
use ncchannel::ads::frame::AmsAddr;
use ncchannel::ads::ServerConfig;

/// A program several times the 4094-byte buffer, with LF line ends and no final line end:
/// parameter blocks with a short move every 50 lines, so the channel executes it in a
/// fraction of a second of real time yet still lags a client that writes as fast as it can.
fn program(lines: usize) -> String {
    let mut s = String::new();
    for i in 1..lines {
        if i % 50 == 0 {
            s.push_str(&format!(
                "N{} G01 X{}.{:03} F6000\n",
                i * 10,
                i % 3,
                i % 1000
            ));
        } else {
            s.push_str(&format!(
                "N{} P{} = {}.{:03}\n",
                i * 10,
                1 + i % 3,
                i % 97,
                i % 1000
            ));
        }
    }
    s.push_str("M30");
    s
}

/// Wait until the program has ended (READY again), then stop the channels and return the
/// lines channel 1 executed and its writes refused with 11012.
fn executed(channels: Channels) -> (Vec<String>, u64) {
    channels.wait_for(1, Duration::from_secs(60), |s| {
        s.state == State::Ready && s.program.is_none()
    });
    let events = channels.events();
    (block_texts(&events), refusals(&events, 11012))
}

/// The lines of `text`, as the channel's block events name them.
fn lines_of(text: &str) -> Vec<String> {
    text.lines().map(str::to_string).collect()
}

fn crlf(text: &str) -> Vec<u8> {
    let mut out = text.replace('\n', "\r\n").into_bytes();
    out.extend_from_slice(b"\r\n");
    out
}

fn connect(srv: &ncchannel::ads::ServerHandle) -> AdsClient {
    let target = AmsAddr {
        port: 553,
        ..device()
    };
    AdsClient::connect(srv.local_addr(), target, None, Duration::from_secs(5)).unwrap()
}

#[test]
fn client_streams_a_large_program_through_a_full_buffer() {
    let (srv, channels) = server_with(ServerConfig::default());
    let mut c = connect(&srv);
    assert!(c.read_device_info().unwrap().name.starts_with("ncchannel"));
    let text = program(800);
    let opts = StreamOptions {
        start_program: Some("streaming.nc".into()),
        ..StreamOptions::default()
    };
    let mut reports = 0;
    let p = client::stream_text(&mut c, text.as_bytes(), &opts, &mut |_| reports += 1).unwrap();
    let expected = crlf(&text);
    assert_eq!(p.bytes_sent, expected.len() as u64);
    assert!(p.rejections > 0, "a slow channel must have pushed back");
    assert!(reports >= 1);
    assert_eq!(channels.status(1).program.as_deref(), Some("streaming.nc"));
    let (blocks, warnings_11012) = executed(channels);
    assert_eq!(
        blocks,
        lines_of(&text),
        "every line executed once, in order"
    );
    assert!(warnings_11012 >= p.rejections);
}

#[test]
fn packets_respect_the_packet_size() {
    let (srv, channels) = server();
    let mut c = connect(&srv);
    let text = program(50);
    let opts = StreamOptions {
        packet_bytes: 64,
        start_program: Some("streaming.nc".into()),
        ..StreamOptions::default()
    };
    let p = client::stream_text(&mut c, text.as_bytes(), &opts, &mut |_| {}).unwrap();
    assert!(p.packets_sent >= (text.len() as u64) / 64);
    assert_eq!(executed(channels).0, lines_of(&text));
}

#[test]
fn a_stopped_channel_stalls_the_stream_with_a_clear_error() {
    let (srv, _b) = server();
    let mut c = connect(&srv);
    let opts = StreamOptions {
        stall_timeout: Duration::from_millis(200),
        ..StreamOptions::default()
    };
    let err = client::stream_text(&mut c, program(600).as_bytes(), &opts, &mut |_| {}).unwrap_err();
    assert!(matches!(err, StreamError::Stalled(_)), "{err}");
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
}

#[test]
fn the_binary_streams_a_file_and_starts_the_program() {
    let (srv, channels) = server();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("part.nc");
    let text = program(400);
    std::fs::write(&file, &text).unwrap();
    let out = bin()
        .arg("stream")
        .arg(&file)
        .args([
            "--target",
            &srv.local_addr().to_string(),
            "--start",
            "--program",
            "streaming.nc",
        ])
        .args([
            "--channel",
            "1",
            "--packet",
            "500",
            "--net-id",
            "5.6.7.8.1.1",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("stream: done"), "{stderr}");
    assert_eq!(executed(channels).0, lines_of(&text));
}

#[test]
fn the_binary_reports_usage_and_errors_with_exit_codes() {
    let (srv, _b) = server();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.nc");
    std::fs::write(&file, "N10 X1\n").unwrap();
    let target = srv.local_addr().to_string();
    let code = |args: &[&str]| {
        bin()
            .arg("stream")
            .args(args)
            .output()
            .unwrap()
            .status
            .code()
    };
    let f = file.to_str().unwrap();
    assert_eq!(code(&[f, "--target", &target, "--packet", "993"]), Some(2));
    assert_eq!(
        code(&[f, "--target", &target, "--net-id", "1.2.3"]),
        Some(2)
    );
    assert_eq!(code(&["/nonexistent/x.nc", "--target", &target]), Some(2));
    // Nobody listens on port 1.
    assert_eq!(code(&[f, "--target", "127.0.0.1:1"]), Some(1));
    // A line too long for one write.
    let long = dir.path().join("long.nc");
    std::fs::write(&long, format!("N10 X{}\n", "1".repeat(1000))).unwrap();
    assert_eq!(
        code(&[long.to_str().unwrap(), "--target", &target]),
        Some(1)
    );
}
