//! `ncchannel stream`: feed an NC file into a channel's stream interface over ADS.

use std::net::{SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use crate::ads::client::{self, AdsClient, StreamOptions, StreamProgress};
use crate::source::stream::MAX_PROGRAM_STREAM_INPUT_SIZE;
use indicatif::ProgressBar;

use crate::ads::frame::AmsAddr;
use crate::ads::objects::PORT_CNC_COM;
use crate::vocab::ams::AmsNetId;

#[derive(Debug, clap::Args)]
pub struct StreamArgs {
    /// NC file to stream (whole lines; LF is sent as CR LF).
    pub file: PathBuf,
    /// ADS/TCP address of the device.
    #[arg(long, default_value = "127.0.0.1:48898")]
    pub target: String,
    /// Target AMS NetId.
    #[arg(long, default_value = "127.0.0.2.1.1")]
    pub net_id: AmsNetId,
    /// Our AMS NetId (default: local IPv4 address + .1.1).
    #[arg(long)]
    pub(crate) source_net_id: Option<AmsNetId>,
    /// Channel number, 1-based (index group 0x20100 + N).
    #[arg(long, default_value_t = 1)]
    pub channel: u16,
    /// Largest packet in bytes (whole lines), 1..=992.
    #[arg(long, value_parser = super::run::packet_bytes, default_value_t = MAX_PROGRAM_STREAM_INPUT_SIZE)]
    pub packet: usize,
    /// Start the streaming program first (AUTOMATIC, program name, ACTIVE).
    #[arg(long)]
    pub start: bool,
    /// The channel's streaming program name (`streaming_prog_file`), used with --start.
    #[arg(long, default_value = "streaming.nc")]
    pub program: String,
    /// Give up after this many seconds in which data waited and the channel ran no program
    /// to take it (a long move that keeps the buffer full is not a stall).
    #[arg(long, default_value_t = 30)]
    pub(crate) stall_secs: u64,
}

/// The progress bar over the file's bytes (a log or a pipe gets the final line alone).
fn progress_bar(total_bytes: u64) -> ProgressBar {
    crate::report::progress::bar(
        total_bytes,
        "stream: [{bar:30}] {bytes}/{total_bytes}  {msg}",
    )
}

fn show_progress(bar: &ProgressBar, p: &StreamProgress) {
    bar.set_position(p.bytes_sent);
    bar.set_message(format!(
        "{} packets, {:.0} B/s, {} rejected (busy)",
        p.packets_sent,
        p.bytes_per_second(),
        p.rejections
    ));
}

pub fn execute(args: StreamArgs) -> ExitCode {
    use super::exit;
    if args.channel == 0 {
        eprintln!("ncchannel stream: --channel is 1-based");
        return ExitCode::from(exit::USAGE);
    }
    let addr: SocketAddr = match args.target.to_socket_addrs().map(|mut a| a.next()) {
        Ok(Some(a)) => a,
        _ => {
            eprintln!(
                "ncchannel stream: --target {:?} is not ADDR:PORT",
                args.target
            );
            return ExitCode::from(exit::USAGE);
        }
    };
    let text = match crate::bounded::read_file(&args.file, super::run::MAX_STREAM_FILE_BYTES) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("ncchannel stream: {}: {e}", args.file.display());
            return ExitCode::from(exit::USAGE);
        }
    };
    let target = AmsAddr {
        net_id: args.net_id,
        port: PORT_CNC_COM,
    };
    let source = args.source_net_id.map(|net_id| AmsAddr {
        net_id,
        port: 32905,
    });
    let mut client = match AdsClient::connect(addr, target, source, Duration::from_secs(5)) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("ncchannel stream: connecting to {addr}: {e}");
            return ExitCode::from(exit::CHANNEL_ERROR);
        }
    };
    let opts = StreamOptions {
        channel: args.channel,
        packet_bytes: args.packet,
        start_program: args.start.then(|| args.program.clone()),
        stall_timeout: Duration::from_secs(args.stall_secs),
        ..StreamOptions::default()
    };
    let bar = progress_bar(text.len() as u64);
    let result = client::stream_text(&mut client, &text, &opts, &mut |p| show_progress(&bar, p));
    bar.finish_and_clear();
    match result {
        Ok(p) => {
            eprintln!(
                "stream: done: {} bytes in {} packets, {:.3} s, {:.0} B/s, {} writes rejected busy (warning 11012), write round trip p50 {:.0} µs p99 {:.0} µs",
                p.bytes_sent,
                p.packets_sent,
                p.elapsed.as_secs_f64(),
                p.bytes_per_second(),
                p.rejections,
                p.write_rtt_us_p50,
                p.write_rtt_us_p99
            );
            ExitCode::from(exit::OK)
        }
        Err(e) => {
            eprintln!("ncchannel stream: {}: {e}", args.file.display());
            ExitCode::from(exit::CHANNEL_ERROR)
        }
    }
}
