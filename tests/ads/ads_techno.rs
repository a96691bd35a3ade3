//! The HLI technology units over ADS (port 851, GEO 551) against a real channel whose table
//! defines M25 as MVS_SVS (TF5200 "Parameterisation of synchronisation types": output before
//! the motion block, the motion starts after the acknowledgement): the PLC's side of the
//! please/done handshake (TF5200 HLI "Technology functions", "Data of the M/H function"), by
//! hand and as `kimblad/TwinSharp` `TwinSharp/CNC/TechnologyProcesses.cs` runs it.

use std::time::{Duration, Instant};

use ads::client::{ReadRequest, WriteRequest};
use ads::notif::{Attributes, TransmissionMode};
use ads::{AmsAddr, AmsNetId};
use ncchannel::vocab::mode::State;

use crate::techno_rig::TechnoRig;

const P: &str = "HLI_Global_Variables.gpCh[0]^";
const UNIT: usize = 47;

fn target(port: u16) -> AmsAddr {
    AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), port)
}

fn handle(plc: &ads::Device<'_>, symbol: &str) -> u32 {
    let mut h = [0u8; 4];
    plc.write_read_exact(0xF003, 0, symbol.as_bytes(), &mut h)
        .unwrap_or_else(|e| panic!("{symbol}: {e}"));
    u32::from_le_bytes(h)
}

fn read(plc: &ads::Device<'_>, h: u32, n: usize) -> Vec<u8> {
    let mut b = vec![0u8; n];
    plc.read_exact(0xF005, h, &mut b).unwrap();
    b
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn ads_code(e: ads::Error) -> u32 {
    match e {
        ads::Error::Ads(_, _, code) => code,
        other => panic!("expected an ADS error, got {other}"),
    }
}

/// Poll `h` (a UINT) until it reads `want`.
fn wait_uint(plc: &ads::Device<'_>, h: u32, want: u16, within: Duration) {
    let deadline = Instant::now() + within;
    loop {
        let v = read(plc, h, 2);
        if u16::from_le_bytes([v[0], v[1]]) == want {
            return;
        }
        assert!(Instant::now() < deadline, "not {want} within {within:?}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Unit 0 as M25 of N20 (program line 2), MVS_SVS, asking.
fn assert_m25(u: &[u8]) {
    assert_eq!(u.len(), UNIT);
    assert_eq!((u[0], u[1]), (1, 0), "please_rw TRUE, done_w FALSE");
    assert_eq!(u16::from_le_bytes([u[2], u[3]]), 1, "type M");
    let d = &u[8..];
    assert_eq!(u32_at(d, 0), 25, "nr");
    assert_eq!(u32_at(d, 8), 20, "block_nr");
    assert_eq!(u32_at(d, 12), 2, "prg_line");
    assert_eq!(u32_at(d, 24), 2, "synch_mode MVS_SVS");
}

#[test]
fn m25_waits_for_the_plc_over_the_hli_and_a_notification_shows_the_unit() {
    let rig = TechnoRig::start();
    let client = rig.client(40200);
    let rx = client.get_notification_channel();
    let plc = client.device(target(851));
    let geo = client.device(target(551));
    let present = handle(&plc, &format!("{P}.head.plc_present_w"));
    plc.write(0xF005, present, &[1]).unwrap();
    assert_eq!(read(&plc, present, 1), [1]);
    assert!(rig.status().techno.plc_present, "the channel has its PLC");
    let mut b = [0u8; 1];
    geo.read_exact(0x123301, 0x0E, &mut b).unwrap();
    assert_eq!(b, [1], "GEO HLD 0x0E");

    let units = handle(&plc, &format!("{P}.techno_unit_std_sync"));
    let used = handle(&plc, &format!("{P}.used_units_std_sync_r"));
    let notification = plc
        .add_notification(
            0xF005,
            units,
            &Attributes::new(
                20 * UNIT,
                TransmissionMode::ServerOnChange,
                Duration::from_millis(1),
                Duration::from_millis(1),
            ),
        )
        .unwrap();
    rig.start_program();
    wait_uint(&plc, used, 1, Duration::from_secs(10));

    // The notification shows the filled unit.
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let n = rx
            .recv_timeout(left)
            .expect("a sample with the unit filled");
        let filled = n
            .samples()
            .filter(|s| s.handle == notification)
            .any(|s| s.data.len() == 20 * UNIT && s.data[0] == 1);
        if filled {
            let s = n.samples().find(|s| s.handle == notification).unwrap();
            assert_m25(&s.data[..UNIT]);
            break;
        }
    }

    let unit0 = handle(&plc, &format!("{P}.techno_unit_std_sync[0]"));
    assert_m25(&read(&plc, unit0, UNIT));
    let ty = handle(&plc, &format!("{P}.techno_unit_std_sync[0].type"));
    assert_eq!(read(&plc, ty, 2), [1, 0]);
    let data = handle(
        &plc,
        &format!("{P}.techno_unit_std_sync[0].attribut_r.data"),
    );
    assert_eq!(u32_at(&read(&plc, data, 39), 0), 25);
    geo_unit_elements(&geo);

    // MVS_SVS: the motion of N20 waits at X10 for the acknowledgement.
    rig.wait_for(Duration::from_secs(5), |s| {
        s.positions
            .iter()
            .any(|&(a, v)| a == 'X' && (v - 10.0).abs() < 1e-6)
    });
    let hold = Instant::now() + Duration::from_millis(150);
    while Instant::now() < hold {
        assert!(
            (rig.x() - 10.0).abs() < 1e-6,
            "moved before the acknowledgement"
        );
        assert_eq!(rig.status().state, State::Active);
    }

    // A read-only part refuses writes.
    assert_eq!(
        ads_code(plc.write(0xF005, used, &[0, 0]).unwrap_err()),
        0x704
    );
    assert_eq!(ads_code(plc.write(0xF005, ty, &[2, 0]).unwrap_err()), 0x704);

    let please = handle(&plc, &format!("{P}.techno_unit_std_sync[0].please_rw"));
    let done = handle(&plc, &format!("{P}.techno_unit_std_sync[0].done_w"));
    // One sum read (0xF080) sees the same live unit; one sum write (0xF081) fetches and
    // acknowledges it.
    let (mut u, mut one, mut n) = ([0u8; 2], [0u8; UNIT], [0u8; 1]);
    let mut reads = [
        ReadRequest::new(0xF005, used, &mut u),
        ReadRequest::new(0xF005, unit0, &mut one),
        ReadRequest::new(0xF005, present, &mut n),
    ];
    plc.read_multi(&mut reads).unwrap();
    assert_eq!(reads[0].data().unwrap(), [1, 0]);
    assert_m25(reads[1].data().unwrap());
    assert_eq!(reads[2].data().unwrap(), [1]);
    plc.write(0xF005, please, &[0]).unwrap();
    assert_eq!(read(&plc, please, 1), [0], "fetched");
    assert!((rig.x() - 10.0).abs() < 1e-6, "fetched is not acknowledged");
    let mut writes = [
        WriteRequest::new(0xF005, please, &[0]),
        WriteRequest::new(0xF005, done, &[1]),
    ];
    plc.write_multi(&mut writes).unwrap();
    writes.iter().for_each(|w| w.ensure().unwrap());
    rig.wait_until_ended();
    wait_uint(&plc, used, 0, Duration::from_secs(5));
    plc.delete_notification(notification).unwrap();
}

#[test]
fn done_w_with_nothing_waiting_changes_nothing() {
    let rig = TechnoRig::start();
    let client = rig.client(40201);
    let plc = client.device(target(851));
    let done = handle(&plc, &format!("{P}.techno_unit_std_sync[3].done_w"));
    let late_done = handle(&plc, &format!("{P}.techno_unit_late_sync[9].done_w"));
    plc.write(0xF005, done, &[1]).unwrap();
    plc.write(0xF005, late_done, &[1]).unwrap();
    assert_eq!(read(&plc, done, 1), [0], "the channel ignored it");
    assert_eq!(read(&plc, late_done, 1), [0]);
    let before = rig.status().techno;
    assert!(before.std.iter().all(|u| !u.done && !u.please));
    assert_eq!(before.used_std, 0);
    let late = handle(&plc, &format!("{P}.techno_unit_late_sync"));
    assert_eq!(read(&plc, late, 10 * UNIT), vec![0; 10 * UNIT]);
    // Whole units and arrays are read-only; a too long write is refused.
    let unit = handle(&plc, &format!("{P}.techno_unit_std_sync[3]"));
    assert_eq!(ads_code(plc.write(0xF005, unit, &[0]).unwrap_err()), 0x704);
    assert_eq!(
        ads_code(plc.write(0xF005, done, &[1, 1]).unwrap_err()),
        0x705
    );
    let used_late = handle(&plc, &format!("{P}.used_units_late_sync_r"));
    assert_eq!(
        ads_code(plc.write(0xF005, used_late, &[1, 0]).unwrap_err()),
        0x704
    );
}

/// `kimblad/TwinSharp` `TwinSharp/CNC/TechnologyProcesses.cs`, replayed request by request:
/// handles for the two MAXIDX constants, `techno_unit_std_sync` and `used_units_std_sync_r`;
/// the constants read as `int`; AddDeviceNotification on the array with `[MAXIDX]` units
/// (OnChange, 25 ms); on a notification read the used count, and for each of the first `used`
/// units of type M: a handle for `[i].please_rw`, write FALSE, then (the application's
/// `AcknowledgeTecnologyUnit`) a handle for `[i].done_w`, write TRUE.
#[test]
fn twinsharp_technology_processes_acknowledges_m25() {
    let rig = TechnoRig::start();
    let client = rig.client(40202);
    let rx = client.get_notification_channel();
    let plc = client.device(target(851));
    // The PLC program itself sets plc_present (TwinSharp leaves it to the PLC).
    let present = handle(&plc, &format!("{P}.head.plc_present_w"));
    plc.write(0xF005, present, &[1]).unwrap();

    let max_h = handle(&plc, "HLI_Global_Constants.HLI_TU_CH_STD_SYNC_MAXIDX");
    let len_h = handle(&plc, "HLI_Global_Constants.HLI_TECH_UNIT_CH_MAXIDX");
    let units = handle(&plc, &format!("{P}.techno_unit_std_sync"));
    let used = handle(&plc, &format!("{P}.used_units_std_sync_r"));
    let maxidx = i32::from_le_bytes(read(&plc, max_h, 4).try_into().unwrap());
    let unit_len = i32::from_le_bytes(read(&plc, len_h, 4).try_into().unwrap());
    assert_eq!((maxidx, unit_len), (19, 38));
    let n = usize::try_from(maxidx).unwrap();
    let notification = plc
        .add_notification(
            0xF005,
            units,
            &Attributes::new(
                UNIT * n,
                TransmissionMode::ServerOnChange,
                Duration::from_millis(25),
                Duration::from_millis(25),
            ),
        )
        .unwrap();
    rig.start_program();

    let deadline = Instant::now() + Duration::from_secs(10);
    let mut acknowledged = Vec::new();
    while acknowledged.is_empty() {
        let left = deadline.saturating_duration_since(Instant::now());
        let note = rx
            .recv_timeout(left)
            .expect("a notification with an M to acknowledge");
        for sample in note.samples().filter(|s| s.handle == notification) {
            assert_eq!(sample.data.len(), UNIT * n);
            let count = usize::from(u16::from_le_bytes(read(&plc, used, 2).try_into().unwrap()));
            for i in 0..count.min(n) {
                let u = &sample.data[i * UNIT..(i + 1) * UNIT];
                if u16::from_le_bytes([u[2], u[3]]) != 1 || u[0] == 0 {
                    continue;
                }
                // ReadMHinfo: the first 32 bytes of MSTH_PROCESS_CH.
                let nr = u32_at(&u[8..], 0);
                let p = handle(&plc, &format!("{P}.techno_unit_std_sync[{i}].please_rw"));
                plc.write(0xF005, p, &[0]).unwrap();
                // The motion of N20 waits for the acknowledgement at X10.
                rig.wait_for(Duration::from_secs(5), |s| {
                    s.positions
                        .iter()
                        .any(|&(a, v)| a == 'X' && (v - 10.0).abs() < 1e-6)
                });
                let d = handle(&plc, &format!("{P}.techno_unit_std_sync[{i}].done_w"));
                plc.write(0xF005, d, &[1]).unwrap();
                acknowledged.push(nr);
            }
        }
    }
    assert_eq!(acknowledged, [25]);
    rig.wait_until_ended();
    plc.delete_notification(notification).unwrap();
}

/// The HLD mirror while M25 waits: used_units_std_sync_r (0x03) and unit 0's please (0x04);
/// the unit's elements, techno.std_sync[0] from 0x3F on (type, please, done, m_h.nr,
/// m_h.time, m_h.block_nr, m_h.prg_line_nr, m_h.add_value); an empty unit; the last element,
/// late_sync[9]::nr_late_sync at 0x138.
fn geo_unit_elements(geo: &ads::Device<'_>) {
    let (mut b, mut w, mut d) = ([0u8; 1], [0u8; 2], [0u8; 4]);
    geo.read_exact(0x123301, 0x03, &mut w).unwrap();
    assert_eq!(w, [1, 0]);
    geo.read_exact(0x123301, 0x04, &mut b).unwrap();
    assert_eq!(b, [1]);
    geo.read_exact(0x123301, 0x3F, &mut w).unwrap();
    assert_eq!(w, [1, 0], "std_sync[0]::type M");
    geo.read_exact(0x123301, 0x40, &mut b).unwrap();
    assert_eq!(b, [1], "std_sync[0]::please");
    for (offset, want) in [(0x42, 25u32), (0x44, 20), (0x45, 2)] {
        geo.read_exact(0x123301, offset, &mut d).unwrap();
        assert_eq!(u32::from_le_bytes(d), want, "HLD 0x{offset:X}");
    }
    geo.read_exact(0x123301, 0x3F + 8, &mut w).unwrap();
    assert_eq!(w, [0, 0]);
    geo.read_exact(0x123301, 0x138, &mut w).unwrap();
    assert_eq!(w, [0, 0]);
}
