//! Real channels behind the object tables' unit tests: a [`Machine`] built from parameter
//! lists in a temporary folder, ticking in real time (1 ms, the lists' default) on its own
//! thread and reached through a [`ChannelBackend`], as `ncchannel serve` runs them. Each
//! channel has the streaming program `streaming.nc` and the default axes X Y Z.

use std::sync::Arc;

use super::backend::CncBackend;
use crate::machine::remote::Ticking;
use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;

/// The running channels; dropping it stops the runtime.
pub(crate) struct TestChannels {
    pub backend: Arc<dyn CncBackend>,
    _ticking: Ticking,
    _dir: tempfile::TempDir,
}

/// `n` channels in AUTOMATIC / READY, streaming on.
pub(crate) fn channels(n: u16) -> TestChannels {
    let dir = tempfile::tempdir().expect("temporary folder");
    let params = dir.path().join("params");
    std::fs::create_dir_all(&params).expect("params folder");
    std::fs::create_dir_all(dir.path().join("nc")).expect("nc folder");
    let mut startup = format!("kanal_anzahl {n}\n");
    for i in 0..n {
        startup.push_str(&format!(
            "sda_mds[{i}] channel{ch}.lis\npfad[{i}].prg[0] ../nc\npfad[{i}].typ[0] 0x03\n\
             pfad[{i}].prioritaet[0] 0\n",
            ch = i + 1
        ));
        std::fs::write(
            params.join(format!("channel{}.lis", i + 1)),
            "streaming_prog_file streaming.nc\n",
        )
        .expect("channel list");
    }
    std::fs::write(params.join("startup.lis"), startup).expect("start-up list");
    let config = crate::params::load(&params.join("startup.lis")).expect("valid lists");
    let loader = crate::source::loader::Loader::start();
    let chans = crate::setup::channels(&config, false, &loader).expect("channels");
    let period = std::time::Duration::from_micros(config.runtime.cycle_period_us);
    let machine = Machine::new(chans, EventLog::disabled(), StopWhen::Never);
    let (backend, ticking) = Ticking::start(machine, period).expect("runtime thread");
    TestChannels {
        backend: Arc::new(backend),
        _ticking: ticking,
        _dir: dir,
    }
}
