//! SIGINT and SIGTERM for `receive --listen`: each signal raises the stop request one level
//! (the first lets the transfers in progress finish within the grace period, the second cuts
//! them), on a thread of its own (signal-hook's `Signals` iterator), so the stop can drop the
//! open programs' temporary files instead of exiting from a signal handler.

use std::io;
use std::net::{Ipv4Addr, SocketAddr, TcpStream};
use std::time::Duration;

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

use super::out::say;
use crate::dnc::{StopLevel, StopRequest};

/// Watch for SIGINT/SIGTERM and escalate `stop` on each. A blocking `accept` does not return
/// for a signal, so the first one also connects once to the listener's own address `local`
/// (the std listener has no other portable wake-up); that connection is not taken as a
/// transfer.
pub(crate) fn on_signals(stop: StopRequest, local: SocketAddr, grace: Duration) -> io::Result<()> {
    let mut signals = Signals::new([SIGINT, SIGTERM])?;
    let mut target = local;
    if target.ip().is_unspecified() {
        target.set_ip(Ipv4Addr::LOCALHOST.into());
    }
    std::thread::Builder::new()
        .name("receive-stop".into())
        .spawn(move || {
            for _ in signals.forever() {
                match stop.escalate() {
                    StopLevel::Graceful => {
                        // Said after the request is raised: whoever waits for this line may
                        // send the second signal.
                        say(format_args!(
                            "ncchannel receive: stopping: no new transfer; the transfers in progress get {:.1} s more (a second signal cuts them)",
                            grace.as_secs_f64()
                        ));
                        let _ = TcpStream::connect_timeout(&target, Duration::from_secs(1));
                    }
                    StopLevel::Now => say(format_args!(
                        "ncchannel receive: stopping now: the transfers in progress are cut"
                    )),
                    StopLevel::Run => {}
                }
            }
        })?;
    Ok(())
}
