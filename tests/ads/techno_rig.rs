//! A channel whose technology table has M25 as MVS_SVS, behind a server on a loopback port,
//! for the tests of the HLI technology units (tests/ads/ads_techno.rs and the real clients in
//! tests/ads_clients). Included by path from both test crates.
#![allow(dead_code)]

use std::sync::Arc;
use std::time::{Duration, Instant};

use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};
use ncchannel::ads::backend::{CncBackend, Op, Status};
use ncchannel::ads::{spawn, ServerConfig, ServerHandle};
use ncchannel::machine::remote::Ticking;
use ncchannel::machine::{Machine, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::vocab::mode::State;
use ncchannel::vocab::techno::{FunctionDef, SyncSpec, SyncType, TechnoTable};

use crate::support::ads::Params;

pub const PROGRAM: &str = "N10 G01 X10 F6000\nN20 X20 M25\nN30 X30\nM30\n";

/// One channel whose technology table has M25 as MVS_SVS (set on the loaded configuration,
/// as the channel list's `m_synch[25] 0x2` would), behind a server on a loopback port.
pub struct TechnoRig {
    pub server: ServerHandle,
    pub backend: Arc<dyn CncBackend>,
    _ticking: Ticking,
    _params: Params,
}

impl TechnoRig {
    pub fn start() -> TechnoRig {
        let params = Params::new(1);
        params.program("techno.nc", PROGRAM);
        let mut config = ncchannel::params::load(&params.startup()).unwrap();
        config.channels[0].techno = TechnoTable {
            m: vec![(
                25,
                FunctionDef::new(SyncSpec {
                    sync: SyncType::MvsSvs,
                    plc_info: false,
                }),
            )],
            ..TechnoTable::kernel_defaults()
        };
        let channels = ncchannel::channels(&config, true, &ncchannel::Loader::start()).unwrap();
        let machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
        let period = Duration::from_micros(config.runtime.cycle_period_us);
        let (backend, ticking) = Ticking::start(machine, period).unwrap();
        let backend: Arc<dyn CncBackend> = Arc::new(backend);
        let server = spawn(
            ServerConfig {
                bind: "127.0.0.1:0".parse().unwrap(),
                ..ServerConfig::default()
            },
            Arc::clone(&backend),
        )
        .unwrap();
        TechnoRig {
            server,
            backend,
            _ticking: ticking,
            _params: params,
        }
    }

    pub fn status(&self) -> Status {
        self.backend.status(1).unwrap()
    }

    pub fn x(&self) -> f64 {
        self.status()
            .positions
            .iter()
            .find(|(a, _)| *a == 'X')
            .map(|p| p.1)
            .unwrap()
    }

    /// Start `techno.nc`.
    pub fn start_program(&self) {
        self.backend
            .command(1, Op::Start("techno.nc".into()))
            .unwrap();
    }

    /// Wait (bounded) until the channel's status satisfies `done`.
    pub fn wait_for(&self, within: Duration, done: impl Fn(&Status) -> bool) -> Status {
        let deadline = Instant::now() + within;
        loop {
            let s = self.status();
            if done(&s) {
                return s;
            }
            assert!(
                Instant::now() < deadline,
                "not reached within {within:?}: {s:?}"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// The program ran to its end: READY again at X30.
    pub fn wait_until_ended(&self) {
        self.wait_for(Duration::from_secs(10), |s| {
            s.state == State::Ready
                && s.positions
                    .iter()
                    .any(|&(a, v)| a == 'X' && (v - 30.0).abs() < 1e-6)
        });
    }

    pub fn client(&self, port: u16) -> Client {
        Client::new(
            self.server.local_addr(),
            Timeouts::new(Duration::from_secs(5)),
            Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), port)),
        )
        .unwrap()
    }
}
