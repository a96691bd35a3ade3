//! What TwinSharp's `new CNC(target)` does on the wire, request by request, against the real
//! channels through an independent client (the `ads` crate 0.4). The sequence is taken from
//! `kimblad/TwinSharp` `TwinSharp/CNC/CNC.cs` (`CreateComDictionary`), `CncChannel.cs` and the
//! constructors it calls (`Interpolator.cs`, `OperationModeManager.cs`, `BackwardsOnPath.cs`,
//! `DeleteDistanceToGo.cs`, `TechnologyProcesses.cs`, `ErrorManagement.cs`,
//! `ManualOperation.cs`), `CncAxis.cs` (`AxisStatus.cs`, `ExternalAxisCommanding.cs`).
//!
//! Also: every record of the description table is read back and its object read at its
//! address with its size, and the type text agrees with the size.

use crate::support::ads as ads_common;

use std::collections::HashMap;
use std::time::Duration;

use ads::notif::{Attributes, TransmissionMode};
use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};

struct Record {
    size: u32,
    writable: bool,
    group: u32,
    offset: u32,
    ty: String,
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b)
        .trim_end_matches('\0')
        .to_string()
}

fn u32_of(b: &[u8]) -> u32 {
    u32::from_le_bytes(b[..4].try_into().unwrap())
}

/// TwinSharp `CNC.CreateComDictionary`: the count at (0x130100, 0), then ONE read of all
/// records at offset 1; `Dictionary.Add` throws on a duplicate name.
fn com_dictionary(com: &ads::Device<'_>) -> HashMap<String, Record> {
    let mut count = [0u8; 4];
    com.read_exact(0x130100, 0, &mut count).unwrap();
    let count = u32::from_le_bytes(count) as usize;
    assert!(count > 50, "{count} objects");
    let mut buf = vec![0u8; count * 84];
    let n = com.read(0x130100, 1, &mut buf).unwrap();
    assert_eq!(n, count * 84, "one bulk read returns every record");
    let mut dict = HashMap::new();
    for r in buf.chunks_exact(84) {
        let name = text(&r[20..52]);
        let rec = Record {
            size: u32_of(&r[4..8]),
            writable: u16::from_le_bytes([r[8], r[9]]) != 0,
            group: u32_of(&r[12..16]),
            offset: u32_of(&r[16..20]),
            ty: text(&r[52..84]),
        };
        assert!(
            dict.insert(name.clone(), rec).is_none(),
            "duplicate name {name}"
        );
    }
    dict
}

fn read_named(
    com: &ads::Device<'_>,
    dict: &HashMap<String, Record>,
    name: &str,
    size: usize,
) -> Vec<u8> {
    let r = dict.get(name).unwrap_or_else(|| panic!("{name} resolves"));
    assert_eq!(
        r.size as usize, size,
        "{name}: the type TwinSharp reads it with"
    );
    let mut b = vec![0u8; size];
    com.read_exact(r.group, r.offset, &mut b).unwrap();
    b
}

/// A PLC variable handle (TwinCAT.Ads `CreateVariableHandle`: ReadWrite 0xF003).
fn handle(plc: &ads::Device<'_>, symbol: &str) -> u32 {
    let mut h = [0u8; 4];
    plc.write_read_exact(0xF003, 0, symbol.as_bytes(), &mut h)
        .unwrap_or_else(|e| panic!("{symbol}: {e}"));
    u32::from_le_bytes(h)
}

#[test]
fn new_cnc_sequence_of_twinsharp_succeeds_on_the_wire() {
    let params = ads_common::Params::new(1);
    let served = ads_common::Served::start(params);
    let source = AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40100);
    let client = Client::new(
        served.server.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(source),
    )
    .unwrap();
    let target = |port| AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), port);
    let (geo, sda, com, plc) = (
        client.device(target(551)),
        client.device(target(552)),
        client.device(target(553)),
        client.device(target(851)),
    );
    let _ = sda;

    let dict = com_dictionary(&com);
    let channels = u16::from_le_bytes(
        read_named(&com, &dict, "cnc_number_of_channel_r", 2)
            .try_into()
            .unwrap(),
    );
    let axes = u32_of(&read_named(&com, &dict, "cnc_number_of_axis_r", 4));
    assert_eq!((channels, axes), (1, 3));

    for ch in 1..=u32::from(channels) {
        new_cnc_channel(&geo, &plc, ch);
    }
    for ax in 1..=axes {
        new_cnc_axis(&com, &plc, ax);
    }
    properties_read_with_their_types(&com, &dict);
    every_record_reads_back(&com, &dict);
    drop(client);
    served.finish();
}

/// TwinSharp `CncChannel` for channel `ch` (1-based), constructor by constructor.
fn new_cnc_channel(geo: &ads::Device<'_>, plc: &ads::Device<'_>, ch: u32) {
    let i = ch - 1;
    // Interpolator: the address query, then the element count.
    let mut addr = [0u8; 8];
    let query = [(ch as i32).to_le_bytes(), 0i32.to_le_bytes()].concat();
    geo.write_read_exact(0x121900, 0, &query, &mut addr)
        .unwrap();
    assert_eq!((u32_of(&addr), u32_of(&addr[4..])), (0x121300 + ch, 0));
    let mut n = [0u8; 4];
    geo.read_exact(0x121300 + ch, 0, &mut n).unwrap();

    operation_mode_manager(geo, plc, ch);
    backwards_on_path(plc, i);
    technology_processes_and_errors(plc, i);
    manual_operation(plc, i);
}

/// OperationModeManager: seven handles, InterfaceExists := TRUE.
fn operation_mode_manager(geo: &ads::Device<'_>, plc: &ads::Device<'_>, ch: u32) {
    let i = ch - 1;
    let ms = format!("HLI_Global_Variables.gpCh[{i}]^.channel_mc_control.mode_and_state");
    for s in [
        "state_r",
        "request_r",
        "state_r.mode",
        "state_r.state",
        "command_w",
        "command_semaphor_rw",
    ] {
        handle(plc, &format!("{ms}.{s}"));
    }
    let enable = handle(plc, &format!("{ms}.enable_w"));
    plc.write(0xF005, enable, &[1]).unwrap();
    let mut b = [0u8; 1];
    geo.read_exact(0x123300 + ch, 0x21, &mut b).unwrap();
    assert_eq!(b, [1], "GEO mirrors enable_w");
    let mut req = [0u8; 327];
    plc.read_exact(0xF005, handle(plc, &format!("{ms}.request_r")), &mut req)
        .unwrap();
}

/// BackwardsOnPath: 13 handles; DeleteDistanceToGo: 3.
fn backwards_on_path(plc: &ads::Device<'_>, i: u32) {
    let bahn = format!("HLI_Global_Variables.gpCh[{i}]^.bahn_mc_control");
    for s in [
        "backward_motion.command_w",
        "backward_motion.enable_w",
        "backward_motion.state_r",
        "simulate_motion.command_w",
        "simulate_motion.state_r",
        "backward_storage_off.command_w",
        "backward_storage_off.state_r",
        "ext_command_speed.command_w",
        "ext_command_speed.enable_w",
        "ext_command_speed.state_r",
        "ext_command_speed_valid.command_w",
        "ext_command_speed_valid.enable_w",
        "ext_command_speed_valid.state_r",
        "delete_distance_to_go.command_w",
        "delete_distance_to_go.state_r",
        "delete_distance_to_go.enable_w",
    ] {
        handle(plc, &format!("{bahn}.{s}"));
    }
}

/// TechnologyProcesses: two constants, two handles, a notification on the array;
/// ErrorManagement: satz_r, semaphor_rw and a notification on the semaphore.
fn technology_processes_and_errors(plc: &ads::Device<'_>, i: u32) {
    let p = format!("HLI_Global_Variables.gpCh[{i}]^");
    let maxidx = handle(plc, "HLI_Global_Constants.HLI_TU_CH_STD_SYNC_MAXIDX");
    let unit_len = handle(plc, "HLI_Global_Constants.HLI_TECH_UNIT_CH_MAXIDX");
    let tu = handle(plc, &format!("{p}.techno_unit_std_sync"));
    handle(plc, &format!("{p}.used_units_std_sync_r"));
    let mut v = [0u8; 4];
    plc.read_exact(0xF005, maxidx, &mut v).unwrap();
    let maxidx = u32::from_le_bytes(v) as usize;
    assert_eq!(maxidx, 19);
    plc.read_exact(0xF005, unit_len, &mut v).unwrap();
    let on_change = |len| {
        Attributes::new(
            len,
            TransmissionMode::ServerOnChange,
            Duration::from_millis(25),
            Duration::from_millis(25),
        )
    };
    plc.add_notification(0xF005, tu, &on_change(47 * maxidx))
        .unwrap();

    handle(plc, &format!("{p}.mc_error.satz_r"));
    let sem = handle(plc, &format!("{p}.mc_error.semaphor_rw"));
    plc.add_notification(0xF005, sem, &on_change(1)).unwrap();
}

/// ManualOperation: activation, tip, jog, 11 keys, rapid key.
fn manual_operation(plc: &ads::Device<'_>, i: u32) {
    let hb = format!("HLI_Global_Variables.gpCh[{i}]^.hb_mc_control");
    let mut units = vec![
        "activation".to_string(),
        "tip_parameter".into(),
        "jog_parameter".into(),
    ];
    units.extend((0..11).map(|k| format!("key[{k}]")));
    units.push("rapid_key".into());
    for u in units {
        for s in ["enable_w", "command_w", "command_semaphor_rw"] {
            handle(plc, &format!("{hb}.{u}.{s}"));
        }
    }
}

/// TwinSharp `CncAxis` for axis `ax` (1-based).
fn new_cnc_axis(com: &ads::Device<'_>, plc: &ads::Device<'_>, ax: u32) {
    // AxisStatus: the channel of the axis at (0x120200, 0x10000·ax + 0x0F).
    let mut c = [0u8; 2];
    com.read_exact(0x120200, 0x10000 * ax + 0x0F, &mut c)
        .unwrap();
    assert_eq!(u16::from_le_bytes(c), 1);
    // ExternalAxisCommanding: four handles.
    let add = format!(
        "HLI_Global_Variables.gpAx[{}]^.lr_mc_control.add_cmd_values",
        ax - 1
    );
    for s in [
        "command_w",
        "enable_w",
        "command_w.m_add_pos_value",
        "command_w.m_add_speed_value",
    ] {
        handle(plc, &format!("{add}.{s}"));
    }
}

/// The names TwinSharp's properties look up, read with the type they read them with.
fn properties_read_with_their_types(com: &ads::Device<'_>, dict: &HashMap<String, Record>) {
    for (name, size) in [
        ("cnc_tick_counter_r", 4),
        ("cnc_cycle_time_r", 4),
        ("cnc_version_r", 24),
        ("cnc_number_of_axis_max_r", 4),
        ("cnc_number_of_spindle_max_r", 4),
        ("cnc_number_of_channel_max_r", 2),
        ("mc_block_count_r", 4),
        ("mc_command_feedrate_r", 8),
        ("mc_active_feedrate_r", 8),
        ("mc_command_block_ignore_r", 4),
        ("mc_active_execution_mode_r", 4),
        ("mc_command_execution_mode_r", 4),
    ] {
        read_named(com, dict, name, size);
    }
    assert_eq!(
        u32_of(&read_named(com, dict, "cnc_cycle_time_r", 4)),
        1000,
        "µs"
    );
    assert!(text(&read_named(com, dict, "cnc_version_r", 24)).starts_with("ncchannel"));
    for name in [
        "mc_command_block_ignore_w",
        "mc_command_execution_mode_w",
        "mc_command_M01_stop_enable_w",
    ] {
        assert!(dict[name].writable, "{name}");
    }
    // TwinSharp `BlockSearch.cs` reads these with `ReadAny<double>` / `<bool>` / `<uint>`.
    for (name, size) in [
        ("mc_cmd_bs_covered_distance_r", 8),
        ("mc_cmd_bs_distance_prog_start_r", 8),
        ("mc_cmd_bs_breakpoint_position_r", 8),
        ("mc_cmd_bs_auto_return_r", 1),
        ("mc_cmd_bs_no_hold_at_restart_r", 1),
        ("mc_cmd_bs_deviation_max_r", 4),
    ] {
        read_named(com, dict, name, size);
    }
}

/// Every record read back at its address with its size; type text agrees with size.
fn every_record_reads_back(com: &ads::Device<'_>, dict: &HashMap<String, Record>) {
    for (name, r) in dict {
        let fixed = match r.ty.as_str() {
            "BOOL" | "BYTE" => Some(1),
            "WORD" | "INT" => Some(2),
            "DWORD" | "DINT" => Some(4),
            "LWORD" | "LREAL" => Some(8),
            // The kernel's text for structures, arrays and triggers: a trigger is 0 bytes.
            "NONE" if r.writable => Some(0),
            "NONE" | "STRING" => None,
            other => panic!("{name}: unknown type {other}"),
        };
        if let Some(size) = fixed {
            assert_eq!(r.size, size, "{name}: {} is {size} bytes", r.ty);
        }
        let mut buf = vec![0u8; r.size as usize];
        let got = com.read(r.group, r.offset, &mut buf);
        let readable = !r.writable || name.ends_with("_rw");
        if readable {
            assert_eq!(
                got.unwrap_or_else(|e| panic!("{name}: {e}")),
                r.size as usize,
                "{name}"
            );
        } else {
            let code = match got.unwrap_err() {
                ads::Error::Ads(_, _, c) => c,
                e => panic!("{name}: {e}"),
            };
            assert_eq!(code, 0x704, "{name}: write-only");
        }
    }
}

/// A channel's mode and state as `state_r` shows them (mode, state).
fn mode_state(plc: &ads::Device<'_>, ms: &str) -> (u32, u32) {
    let mut b = [0u8; 8];
    plc.read_exact(0xF005, handle(plc, &format!("{ms}.state_r")), &mut b)
        .unwrap();
    (u32_of(&b), u32_of(&b[4..]))
}

/// TwinSharp `OperationModeManager.SetModeAndState`: `command_w`, then the semaphore TRUE.
fn set_mode_and_state(plc: &ads::Device<'_>, ms: &str, to_mode: u32, to_state: u32) {
    let mut cmd = [0u8; 327];
    cmd[8..12].copy_from_slice(&to_mode.to_le_bytes());
    cmd[12..16].copy_from_slice(&to_state.to_le_bytes());
    plc.write(0xF005, handle(plc, &format!("{ms}.command_w")), &cmd)
        .unwrap();
    plc.write(
        0xF005,
        handle(plc, &format!("{ms}.command_semaphor_rw")),
        &[1],
    )
    .unwrap();
}

/// The error ids `mc_error` hands the PLC, taking each (semaphore FALSE) until none is left.
fn posted_errors(plc: &ads::Device<'_>) -> Vec<u32> {
    let p = "HLI_Global_Variables.gpCh[0]^.mc_error";
    let sem = handle(plc, &format!("{p}.semaphor_rw"));
    let id = handle(plc, &format!("{p}.satz_r.kopf.error_id"));
    let mut out = Vec::new();
    for _ in 0..16 {
        let mut s = [0u8; 1];
        plc.read_exact(0xF005, sem, &mut s).unwrap();
        if s == [0] {
            break;
        }
        let mut v = [0u8; 4];
        plc.read_exact(0xF005, id, &mut v).unwrap();
        out.push(u32::from_le_bytes(v));
        plc.write(0xF005, sem, &[0]).unwrap();
    }
    out
}

/// TwinSharp `OperationModeManager.Reset()` request by request while a program runs: read
/// `state_r.mode`, command STANDBY / PROCESS_SELECTED, then the old mode / PROCESS_SELECTED.
/// The program stops (READY in the old mode) and no refusal is posted. Before it, a mode
/// change through COM while ACTIVE is refused for good (0x707) with 270061 posted once.
#[test]
fn twinsharp_reset_stops_a_running_program() {
    let served = ads_common::Served::start(ads_common::Params::new(1));
    let client = Client::new(
        served.server.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40101)),
    )
    .unwrap();
    let target = |port| AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), port);
    let (com, plc) = (client.device(target(553)), client.device(target(851)));
    let ms = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state";
    com.write(0x20101, 0x104, &2i32.to_le_bytes()).unwrap();
    com.write(0x20101, 0x108, b"streaming.nc\0").unwrap();
    com.write(0x20101, 0x105, &4i32.to_le_bytes()).unwrap();
    assert_eq!(mode_state(&plc, ms), (2, 4), "AUTOMATIC / ACTIVE");
    // A mode change while ACTIVE through COM: refused for good (0x707), 270061 posted.
    let manual = com.write(0x20101, 0x104, &4i32.to_le_bytes());
    assert!(
        matches!(manual, Err(ads::Error::Ads(_, _, 0x707))),
        "mode change while ACTIVE: {manual:?}"
    );
    assert_eq!(posted_errors(&plc), [270_061]);

    let mut mode = [0u8; 4];
    plc.read_exact(
        0xF005,
        handle(&plc, &format!("{ms}.state_r.mode")),
        &mut mode,
    )
    .unwrap();
    set_mode_and_state(&plc, ms, 1, 2);
    assert_eq!(mode_state(&plc, ms), (1, 3), "STANDBY / READY: stopped");
    set_mode_and_state(&plc, ms, u32_of(&mode), 2);
    assert_eq!(mode_state(&plc, ms), (2, 3), "AUTOMATIC / READY");
    assert_eq!(posted_errors(&plc), Vec::<u32>::new(), "nothing refused");
    drop(client);
    served.finish();
}

/// A start while the channel is in ERROR cannot succeed on retry: 0x707 (not 0x708), and
/// the PLC's `mc_error` hands over 270061 beside the error that stopped the channel.
#[test]
fn start_in_error_is_not_ready_with_the_hli_record() {
    let served = ads_common::Served::start(ads_common::Params::new(1));
    let client = Client::new(
        served.server.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40102)),
    )
    .unwrap();
    let target = |port| AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), port);
    let (com, plc) = (client.device(target(553)), client.device(target(851)));
    let ms = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state";
    assert_eq!(posted_errors(&plc), Vec::<u32>::new());
    com.write(0x20101, 0x104, &2i32.to_le_bytes()).unwrap();
    com.write(0x20101, 0x108, b"streaming.nc\0").unwrap();
    com.write(0x20101, 0x105, &4i32.to_le_bytes()).unwrap();
    // A line without CR LF: error 21476, ERROR.
    assert!(com.write(0x20101, 0x90, b"N10 X1\n").is_err());
    assert_eq!(mode_state(&plc, ms), (2, 6), "AUTOMATIC / ERROR");
    let start = com.write(0x20101, 0x105, &4i32.to_le_bytes());
    assert!(
        matches!(start, Err(ads::Error::Ads(_, _, 0x707))),
        "start in ERROR: {start:?}"
    );
    let mut posted = posted_errors(&plc);
    posted.sort_unstable();
    assert_eq!(posted, [21476, 270_061]);
    drop(client);
    served.finish();
}
