//! The kernel objects HMIs read, served from the channel's model over a real ADS socket with
//! ncchannel's own client: feed hold (COM 0x15/0x16), the program counter (0x44F), the
//! error-message objects (0x257, 0x26), the buffer levels (0x7E, 0x7F, GEO 0x04/0x05), the
//! block-search-by-distance parameters, axis types and PCS positions, the zero offsets
//! `V.G.NP[i].V` on the SDA port, and the description table's type texts.

use std::time::{Duration, Instant};

use crate::support::ads::*;
use ncchannel::ads::client::{start_program, AdsClient};
use ncchannel::ads::frame::AmsAddr;

const CH: u32 = 0x120101;
const IPO: u32 = 0x121301;

pub(crate) fn connect(served: &Served, port: u16) -> AdsClient {
    let target = AmsAddr { port, ..device() };
    AdsClient::connect(
        served.server.local_addr(),
        target,
        None,
        Duration::from_secs(5),
    )
    .unwrap()
}

fn u32_of(c: &mut AdsClient, group: u32, offset: u32) -> u32 {
    u32_at(&c.read(group, offset, 4).unwrap(), 0)
}

fn f64_of(c: &mut AdsClient, group: u32, offset: u32) -> f64 {
    let b = c.read(group, offset, 8).unwrap();
    f64::from_le_bytes(b[..8].try_into().unwrap())
}

fn text_of(c: &mut AdsClient, group: u32, offset: u32, size: u32) -> String {
    let b = c.read(group, offset, size).unwrap();
    assert_eq!(
        b.len(),
        size as usize,
        "a STRING({size}) answers its buffer"
    );
    let end = b.iter().position(|&x| x == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
}

/// The ADS result code a refused request answered.
fn refused(r: Result<impl std::fmt::Debug, ncchannel::ads::client::ClientError>) -> u32 {
    match r {
        Err(e) => e.ads_result().map(|r| r.0).unwrap_or_else(|| panic!("{e}")),
        Ok(v) => panic!("accepted: {v:?}"),
    }
}

/// Poll `read` until `done` holds (generous deadline: the runtime ticks in real time).
fn wait_until(what: &str, mut read: impl FnMut() -> u32, done: impl Fn(u32) -> bool) -> u32 {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let v = read();
        if done(v) {
            return v;
        }
        assert!(Instant::now() < deadline, "{what}: still {v}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn wait_state(c: &mut AdsClient, state: u32) {
    wait_until(
        "mcm_active_state_r",
        || u32_of(c, CH, 0x109),
        |s| s == state,
    );
}

/// Many short slow moves: the lookahead window fills and the program runs for minutes.
fn long_program() -> String {
    let mut s = String::from("G01 F60\n");
    for i in 1..=400 {
        s.push_str(&format!("X{}\n", f64::from(i) * 0.5));
    }
    s.push_str("M30\n");
    s
}

#[test]
fn feed_hold_written_holds_the_channel_and_reads_back() {
    let params = Params::new(1);
    params.program("long.nc", &long_program());
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    assert_eq!(c.read(CH, 0x15, 1).unwrap(), [0], "no feed hold at start");
    assert_eq!(
        refused(c.write(CH, 0x16, &[1])),
        0x707,
        "nothing runs: nothing to hold (yet)"
    );
    start_program(&mut c, 1, "long.nc").unwrap();
    wait_state(&mut c, 4);
    c.write(CH, 0x16, &[1]).unwrap();
    wait_state(&mut c, 5);
    assert_eq!(c.read(CH, 0x15, 1).unwrap(), [1], "mc_command_feedhold_r");
    // Held: the path velocity (GEO interpolator 0x15, µm/s) brakes to zero.
    let mut geo = connect(&served, 551);
    let deadline = Instant::now() + Duration::from_secs(20);
    while f64_of(&mut geo, IPO, 0x15) != 0.0 {
        assert!(Instant::now() < deadline, "motion never stopped");
        std::thread::sleep(Duration::from_millis(2));
    }
    c.write(CH, 0x16, &[1]).unwrap();
    assert_eq!(c.read(CH, 0x15, 1).unwrap(), [1], "repeated: still held");
    c.write(CH, 0x16, &[0]).unwrap();
    wait_state(&mut c, 4);
    assert_eq!(c.read(CH, 0x15, 1).unwrap(), [0], "released");
    c.write(CH, 0x16, &[0]).unwrap();
    assert_eq!(
        u32_of(&mut c, CH, 0x109),
        4,
        "releasing twice changes nothing"
    );
    // An operator start ends the feed hold too.
    c.write(CH, 0x16, &[1]).unwrap();
    wait_state(&mut c, 5);
    c.write(CH, 0x137, &[]).unwrap();
    wait_state(&mut c, 4);
    assert_eq!(
        c.read(CH, 0x15, 1).unwrap(),
        [0],
        "mcm_automatic_resume_w released it"
    );
    assert_eq!(refused(c.read(CH, 0x16, 1)), 0x704, "write-only");
    assert_eq!(refused(c.write(CH, 0x15, &[1])), 0x704, "read-only");
    assert_eq!(refused(c.write(CH, 0x16, &[1, 2, 3])), 0x705);
    c.write(CH, 0x13C, &[]).unwrap();
    wait_state(&mut c, 3);
}

#[test]
fn releasing_the_feed_hold_leaves_a_programmed_stop_held() {
    let params = Params::new(1);
    params.program("m00.nc", "G01 X1 F6000\nM00\nX2\nM30\n");
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    start_program(&mut c, 1, "m00.nc").unwrap();
    wait_state(&mut c, 5);
    assert_eq!(c.read(CH, 0x15, 1).unwrap(), [0], "M00 is no feed hold");
    c.write(CH, 0x16, &[0]).unwrap();
    assert_eq!(u32_of(&mut c, CH, 0x109), 5, "still held at M00");
    assert_eq!(
        refused(c.write(CH, 0x16, &[1])),
        0x707,
        "held by M00: no motion to hold"
    );
    c.write(CH, 0x105, &4i32.to_le_bytes()).unwrap();
    wait_until(
        "mc_program_count_r",
        || u32_of(&mut c, CH, 0x44F),
        |v| v == 1,
    );
}

#[test]
fn program_count_increments_after_each_program_end() {
    let params = Params::new(1);
    params.program("short.nc", "G01 X1 F6000\nM30\n");
    params.program("long.nc", &long_program());
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    assert_eq!(u32_of(&mut c, CH, 0x44F), 0, "mc_program_count_r");
    for n in 1..=2 {
        start_program(&mut c, 1, "short.nc").unwrap();
        wait_until(
            "mc_program_count_r",
            || u32_of(&mut c, CH, 0x44F),
            |v| v == n,
        );
        wait_state(&mut c, 3);
    }
    // A reset is no program end.
    start_program(&mut c, 1, "long.nc").unwrap();
    wait_state(&mut c, 4);
    c.write(CH, 0x13C, &[]).unwrap();
    wait_state(&mut c, 3);
    assert_eq!(u32_of(&mut c, CH, 0x44F), 2);
}

#[test]
fn error_message_objects_show_the_channels_last_error() {
    let params = Params::new(1);
    params.program("bad.nc", "G01 X1 F6000\nG999\nM30\n");
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    assert_eq!(text_of(&mut c, CH, 0x257, 1330), "", "no error yet");
    start_program(&mut c, 1, "bad.nc").unwrap();
    wait_state(&mut c, 6);
    let channel = text_of(&mut c, CH, 0x26, 1330);
    let platform = text_of(&mut c, CH, 0x257, 1330);
    assert!(!channel.is_empty());
    assert_eq!(platform, channel, "cnc_error_message_r = channel 1's");
    let number: String = platform.chars().take_while(char::is_ascii_digit).collect();
    assert!(number.len() >= 4, "starts with the ISG number: {platform}");
    assert_eq!(
        text_of(&mut c, 0x120100, 0x257, 1330),
        platform,
        "platform objects answer in any channel group"
    );
}

#[test]
fn buffer_levels_follow_the_lookahead_window() {
    let params = Params::new(1);
    params.program("long.nc", &long_program());
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    let mut geo = connect(&served, 551);
    assert_eq!(u32_of(&mut c, CH, 0x7F), 0, "mc_slope_buf_level, idle");
    start_program(&mut c, 1, "long.nc").unwrap();
    wait_state(&mut c, 4);
    c.write(CH, 0x16, &[1]).unwrap();
    wait_state(&mut c, 5);
    // Held with 400 blocks to go: the decoder fills the block queue, the window fills, and
    // both stay full. Each level is one value at two addresses (COM and GEO interpolator).
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let slope = [
            u32_of(&mut c, CH, 0x7F),
            u32_of(&mut geo, IPO, 0x04),
            u32_of(&mut c, CH, 0x7F),
        ];
        let ipo = [
            u32_of(&mut c, CH, 0x7E),
            u32_of(&mut geo, IPO, 0x05),
            u32_of(&mut c, CH, 0x7E),
        ];
        if slope[0] > 0 && slope.iter().all(|&v| v == slope[0]) && ipo.iter().all(|&v| v == ipo[0])
        {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "levels never settled: slope {slope:?}, ipo {ipo:?}"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    c.write(CH, 0x13C, &[]).unwrap();
    wait_state(&mut c, 3);
    assert_eq!(u32_of(&mut c, CH, 0x7F), 0, "a reset empties the window");
    assert_eq!(u32_of(&mut geo, IPO, 0x04), 0);
}

#[test]
fn block_search_by_distance_parameters_round_trip() {
    let served = Served::start(Params::new(1));
    let mut c = connect(&served, 553);
    for (w, r, value) in [
        (0x44, 0x45, 1_234_567.5f64),
        (0x4A, 0x62, 250.0),
        (0x7B, 0x7C, 98_765.25),
    ] {
        assert_eq!(f64_of(&mut c, CH, r), 0.0, "0x{r:X} default");
        c.write(CH, w, &value.to_le_bytes()).unwrap();
        assert_eq!(f64_of(&mut c, CH, r), value, "0x{r:X}");
        assert_eq!(
            refused(c.write(CH, w, &(-1.0f64).to_le_bytes())),
            0x706,
            "0x{w:X}: negative"
        );
        assert_eq!(
            refused(c.write(CH, w, &f64::NAN.to_le_bytes())),
            0x706,
            "0x{w:X}: NaN"
        );
        assert_eq!(refused(c.write(CH, w, &[0; 4])), 0x705, "0x{w:X}: LREAL");
        assert_eq!(
            f64_of(&mut c, CH, r),
            value,
            "0x{r:X}: a refusal changes nothing"
        );
    }
    assert_eq!(
        refused(c.write(CH, 0x4A, &1000.5f64.to_le_bytes())),
        0x706,
        "per mil of a block: at most 1000"
    );
    for (w, r) in [(0x4B, 0x63), (0x79, 0x7A)] {
        assert_eq!(c.read(CH, r, 1).unwrap(), [0]);
        c.write(CH, w, &[1]).unwrap();
        assert_eq!(c.read(CH, r, 1).unwrap(), [1], "0x{r:X}");
        c.write(CH, w, &[0]).unwrap();
        assert_eq!(c.read(CH, r, 1).unwrap(), [0], "0x{r:X}");
    }
    c.write(CH, 0x4C, &5000u32.to_le_bytes()).unwrap();
    assert_eq!(u32_of(&mut c, CH, 0x64), 5000, "mc_cmd_bs_deviation_max_r");
    // One search command: the other fields keep their values.
    c.write(CH, 0x5F, &40u32.to_le_bytes()).unwrap();
    assert_eq!(f64_of(&mut c, CH, 0x45), 1_234_567.5);
    assert_eq!(u32_of(&mut c, CH, 0x77), 40);
    assert_eq!(u32_of(&mut c, CH, 0x64), 5000);
}

#[test]
fn axis_types_and_pcs_positions_in_high_resolution() {
    let params = Params::new(1);
    params.program("move.nc", "G01 X12.3456 Y-7.5 Z3 F60000\nM30\n");
    let served = Served::start(params);
    let mut c = connect(&served, 553);
    start_program(&mut c, 1, "move.nc").unwrap();
    wait_until(
        "mc_program_count_r",
        || u32_of(&mut c, CH, 0x44F),
        |v| v == 1,
    );
    for k in 1..=3u32 {
        let ty = c.read(CH, 0x10000 * k + 0x03, 2).unwrap();
        assert_eq!(ty, [1, 0], "mc_axis_{k}_type_r: translator");
        assert_eq!(
            c.read(0x120200 + k, 0x01, 2).unwrap(),
            [1, 0],
            "ac_{k}_type_r"
        );
        assert_eq!(c.read(0x120200, 0x10000 * k + 0x01, 2).unwrap(), [1, 0]);
    }
    let x_hr = f64_of(&mut c, CH, 0x10035);
    assert!((x_hr - 123_456.0).abs() < 1e-3, "X in 0.1 µm: {x_hr}");
    assert_eq!(f64_of(&mut c, CH, 0x10036), x_hr, "commanded = current");
    let y = c.read(CH, 0x20006, 4).unwrap();
    assert_eq!(i32::from_le_bytes(y[..4].try_into().unwrap()), -75_000);
    assert_eq!(f64_of(&mut c, CH, 0x20035), -75_000.0);
}

/// The type text of record `name` in channel 1's description table.
fn record_type(c: &mut AdsClient, name: &str) -> String {
    let count = u32_of(c, 0x130101, 0);
    let all = c.read(0x130101, 1, count * 84).unwrap();
    let field = |r: &[u8], at: usize| {
        let f = &r[at..at + 32];
        let end = f.iter().position(|&b| b == 0).unwrap_or(32);
        String::from_utf8_lossy(&f[..end]).into_owned()
    };
    all.chunks(84)
        .find(|r| field(r, 20) == name)
        .map(|r| field(r, 52))
        .unwrap_or_else(|| panic!("{name} not listed"))
}

#[test]
fn description_records_carry_the_kernels_type_texts() {
    let served = Served::start(Params::new(1));
    let mut c = connect(&served, 553);
    for (name, ty) in [
        ("mcm_active_r", "NONE"),
        ("ncc_stream_fill_r", "NONE"),
        ("ncc_positions_mm_r", "NONE"),
        ("mcm_automatic_stop_w", "NONE"),
        ("mc_program_count_r", "DWORD"),
        ("mc_command_feedhold_r", "BOOL"),
        ("mc_cmd_bs_distance_prog_start_r", "LREAL"),
        ("cnc_error_message_r", "STRING"),
        ("mc_axis_1_type_r", "WORD"),
    ] {
        assert_eq!(record_type(&mut c, name), ty, "{name}");
    }
}

/// One DINT per axis, as TwinSharp `ZeroOffsets.cs` decodes a zero-offset read.
fn dints(b: &[u8]) -> Vec<i32> {
    b.chunks_exact(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn zero_offsets_read_as_twinsharp_reads_them() {
    let params = Params::new(1);
    let list = params.dir.path().join("params/np.lis");
    std::fs::write(
        &list,
        "np_grp[0].achse[0].versch 70000\nnp_grp[1].achse[0].versch 100000\n\
         np_grp[2].achse[2].versch -25000\n",
    )
    .unwrap();
    let startup = std::fs::read_to_string(params.startup()).unwrap();
    std::fs::write(
        params.startup(),
        format!("{startup}zero_offset_list np.lis\n"),
    )
    .unwrap();
    let served = Served::start(params);
    let mut sda = connect(&served, 552);
    let handle = |sda: &mut AdsClient, name: &str| {
        u32_at(
            &sda.read_write(0x122301, 0x46, 4, name.as_bytes()).unwrap(),
            0,
        )
    };
    let g54 = handle(&mut sda, "V.G.NP[1].V");
    assert_eq!(
        handle(&mut sda, "v.g.np[1].v"),
        g54,
        "same name, same handle"
    );
    // TwinSharp: a plain read of 1024 bytes at the handle; the answer has one DINT per axis.
    assert_eq!(
        dints(&sda.read(0x122301, g54, 1024).unwrap()),
        [100_000, 0, 0]
    );
    let g55 = handle(&mut sda, "V.G.NP[2].V");
    assert_eq!(
        dints(&sda.read(0x122301, g55, 1024).unwrap()),
        [0, 0, -25_000]
    );
    let by_name = sda
        .read_write(0x122301, 0x48, 12, b"V.G.NP[2].V\0")
        .unwrap();
    assert_eq!(dints(&by_name), [0, 0, -25_000], "read by name");
    // Group 0 is G53: no offset, whatever the list says (the kernel's numbering).
    let g53 = handle(&mut sda, "V.G.NP[0].V");
    assert_eq!(dints(&sda.read(0x122301, g53, 12).unwrap()), [0, 0, 0]);
    let g59 = handle(&mut sda, "V.G.NP[6].V");
    assert_eq!(dints(&sda.read(0x122301, g59, 12).unwrap()), [0, 0, 0]);
    assert_eq!(refused(sda.read(0x122301, g54, 8)), 0x705, "12 bytes");
    assert_eq!(
        refused(sda.write(0x122301, g54, &[0; 12])),
        0x704,
        "the decoder's table comes from the parameter lists"
    );
    assert_eq!(
        refused(sda.read_write(0x122301, 0x46, 4, b"V.G.NP[7].V")),
        0x70C,
        "G59 is the last group ncchannel has"
    );
}

/// Channel 1's HLD instance on the GEO port.
const HLD: u32 = 0x123301;

/// A handle on port 851 for an HLI symbol of channel 1's mode-and-state unit.
fn unit_handle(plc: &mut AdsClient, member: &str) -> u32 {
    let name = format!("HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.{member}");
    u32_at(&plc.read_write(0xF003, 0, 4, name.as_bytes()).unwrap(), 0)
}

#[test]
fn an_hmi_writes_the_mode_and_state_request_on_the_hld_and_the_plc_reads_it() {
    let served = Served::start(Params::new(1));
    let mut geo = connect(&served, 551);
    let mut plc = connect(&served, 851);
    // request_r.to_mode (0x26), .to_state (0x27), .parameter (0x29), then the semaphore (0x22).
    geo.write(HLD, 0x26, &2u32.to_le_bytes()).unwrap();
    geo.write(HLD, 0x27, &4u32.to_le_bytes()).unwrap();
    geo.write(HLD, 0x29, b"part.nc\0").unwrap();
    geo.write(HLD, 0x22, &[1]).unwrap();
    assert_eq!(
        u32_of(&mut geo, HLD, 0x26),
        2,
        "the HLD reads its request back"
    );
    let to_state = unit_handle(&mut plc, "request_r.to_state");
    assert_eq!(
        u32_of(&mut plc, 0xF005, to_state),
        4,
        "the PLC sees the request"
    );
    let sem = unit_handle(&mut plc, "request_semaphor_rw");
    assert_eq!(plc.read(0xF005, sem, 1).unwrap(), [1]);
    let param = unit_handle(&mut plc, "request_r.parameter");
    assert_eq!(&plc.read(0xF005, param, 8).unwrap()[..8], b"part.nc\0");
    // The PLC takes the request: the semaphore falls on the HLD too.
    plc.write(0xF005, sem, &[0]).unwrap();
    assert_eq!(geo.read(HLD, 0x22, 1).unwrap(), [0]);
    // The command side stays the PLC's: 0x704 on the HLD, too long a value 0x705.
    assert_eq!(refused(geo.write(HLD, 0x2C, &2u32.to_le_bytes())), 0x704);
    assert_eq!(refused(geo.write(HLD, 0x1F, &3u32.to_le_bytes())), 0x704);
    assert_eq!(refused(geo.write(HLD, 0x26, &[0; 5])), 0x705);
    assert_eq!(refused(geo.write(HLD, 0x29, &[b'x'; 301])), 0x705);
}
