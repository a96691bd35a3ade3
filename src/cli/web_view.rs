//! `serve --http`: the live web view started over its own backend into the runtime that
//! serves ADS, for a plain `serve` and for `serve --soak` alike.

use std::process::ExitCode;
use std::sync::Arc;

use crate::http::{ControlAccess, HttpConfig, HttpHandle};
use crate::machine::remote::ChannelBackend;
use crate::runtime::Runtime;

use super::exit;
use super::out::say;

/// Starts the web view of `config` (nothing without one) with `previews` of whole programs
/// when given, and says where it listens; a bind that fails is a usage error.
pub(crate) fn spawn<C: crate::runtime::Cycle>(
    config: Option<HttpConfig>,
    rt: &mut Runtime<C>,
    requests: crossbeam_channel::Sender<crate::machine::Request>,
    channels: u16,
    previews: Option<crate::http::preview::Previewer>,
) -> Result<Option<HttpHandle>, ExitCode> {
    let Some(config) = config else {
        return Ok(None);
    };
    let backend = Arc::new(ChannelBackend::new(requests, channels));
    match crate::http::spawn(&config, backend, Some(rt.live_stats())) {
        Ok(h) => {
            if let Some(p) = previews {
                h.set_previewer(p);
            }
            super::logger::line(format_args!(
                "web view on http://{}/ (controls {})",
                h.local_addr(),
                if config.controls == ControlAccess::Allowed {
                    "on"
                } else {
                    "off"
                }
            ));
            Ok(Some(h))
        }
        Err(e) => {
            say(format_args!("ncchannel serve: --http {}: {e}", config.bind));
            Err(ExitCode::from(exit::USAGE))
        }
    }
}
