//! ADS state control through the `ads` crate (0.4: `write_control`, `get_state`), as a
//! TwinCAT system answers it: WriteControl STOP/RUN/RESET of the PLC runtime on 851, RESET of
//! the CNC task on 553 (every channel reset), CONFIG and RESET (restart) of the system service
//! on 10000 with the extended state read (group 0xF0) and the runtime ports gone in CONFIG.

use crate::support::ads as ads_common;

use std::time::Duration;

use ads::client::AdsState;
use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};

const CH1: u32 = 0x20101;
const ENABLE_W: &str = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.enable_w";

fn handle(plc: &ads::Device<'_>, symbol: &str) -> u32 {
    let mut h = [0u8; 4];
    plc.write_read_exact(0xF003, 0, symbol.as_bytes(), &mut h)
        .unwrap_or_else(|e| panic!("{symbol}: {e}"));
    u32::from_le_bytes(h)
}

/// Channel 1's (mode, state) from COM 0x103.
fn mode_state(com: &ads::Device<'_>) -> (u32, u32) {
    let mut b = [0u8; 8];
    com.read_exact(CH1, 0x103, &mut b).unwrap();
    let w = |at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    (w(0), w(4))
}

fn start_streaming(com: &ads::Device<'_>) {
    com.write(CH1, 0x104, &2i32.to_le_bytes()).unwrap();
    com.write(CH1, 0x108, b"streaming.nc\0").unwrap();
    com.write(CH1, 0x105, &4i32.to_le_bytes()).unwrap();
    assert_eq!(mode_state(com), (2, 4), "AUTOMATIC / ACTIVE");
}

fn error_code(e: &ads::Error) -> Option<u32> {
    match e {
        ads::Error::Ads(_, _, code) => Some(*code),
        _ => None,
    }
}

#[test]
fn write_control_stops_resets_and_restarts_as_twincat_does() {
    let served = ads_common::Served::start(ads_common::Params::new(1));
    let client = Client::new(
        served.server.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40200)),
    )
    .unwrap();
    let target = |port| AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), port);
    let (sys, com, plc) = (
        client.device(target(10000)),
        client.device(target(553)),
        client.device(target(851)),
    );
    for d in [&sys, &com, &plc] {
        assert_eq!(d.get_state().unwrap().0, AdsState::Run);
    }

    // PLC runtime: STOP, RUN; RESET puts the variables back and leaves it in STOP.
    plc.write_control(AdsState::Stop, 0).unwrap();
    assert_eq!(plc.get_state().unwrap().0, AdsState::Stop);
    let mut dd = [0u8; 4];
    plc.read_exact(0xF100, 0, &mut dd).unwrap();
    assert_eq!(dd, [6, 0, 0, 0], "device data shows STOP");
    plc.write_control(AdsState::Run, 0).unwrap();
    assert_eq!(plc.get_state().unwrap().0, AdsState::Run);
    let enable = handle(&plc, ENABLE_W);
    plc.write(0xF005, enable, &[1]).unwrap();
    plc.write_control(AdsState::Reset, 0).unwrap();
    assert_eq!(plc.get_state().unwrap().0, AdsState::Stop);
    let mut b = [9u8; 1];
    plc.read_exact(0xF005, enable, &mut b).unwrap();
    assert_eq!(b, [0], "enable_w back to its initial value");
    plc.write_control(AdsState::Run, 0).unwrap();
    assert_eq!(
        sys.get_state().unwrap().0,
        AdsState::Run,
        "the system runs on"
    );

    // CNC task: RESET resets every channel; the task keeps running.
    start_streaming(&com);
    com.write_control(AdsState::Reset, 0).unwrap();
    assert_eq!(mode_state(&com), (2, 3), "AUTOMATIC / READY");
    assert_eq!(com.get_state().unwrap().0, AdsState::Run);
    let refused = com.write_control(AdsState::Idle, 0).unwrap_err();
    assert_eq!(error_code(&refused), Some(0x706), "{refused}");

    // System service: CONFIG (as adstool `state 15`): the channels reset, the runtime ports
    // are gone; RESET (ads-client setTcSystemToRun) restarts into RUN.
    start_streaming(&com);
    let mut ext = [0u8; 16];
    sys.read_exact(0xF0, 0, &mut ext).unwrap();
    assert_eq!(&ext[0..6], &[5, 0, 0, 0, 0, 0], "RUN, restart index 0");
    sys.write_control(AdsState::Config, 0).unwrap();
    assert_eq!(sys.get_state().unwrap().0, AdsState::Config);
    sys.read_exact(0xF0, 0, &mut ext).unwrap();
    assert_eq!(u16::from_le_bytes([ext[0], ext[1]]), 15);
    let gone = plc.get_state().unwrap_err();
    assert_eq!(error_code(&gone), Some(6), "port 851 in CONFIG: {gone}");
    assert!(com.read_exact(CH1, 0x103, &mut [0u8; 8]).is_err());
    sys.write_control(AdsState::Reset, 0).unwrap();
    assert_eq!(sys.get_state().unwrap().0, AdsState::Run);
    sys.read_exact(0xF0, 0, &mut ext).unwrap();
    assert_eq!(&ext[0..6], &[5, 0, 0, 0, 1, 0], "RUN, restarted once");
    assert_eq!(mode_state(&com), (2, 3), "the channel was reset");
    assert_eq!(plc.get_state().unwrap().0, AdsState::Run);
    drop(client);
    served.finish();
}
