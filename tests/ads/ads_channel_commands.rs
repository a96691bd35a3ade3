//! The COM task's channel commands against the real channels (the `ads` crate as client):
//! single block (one block, then stop until the next start), skip levels wired to the
//! decoder's block-skip mask, block search by N number through `mc_cmd_bs_*` and the execution
//! mode, and the `mc_active_*` objects following execution.

use crate::support::ads as ads_common;

use std::time::{Duration, Instant};

use ads::{AmsAddr, AmsNetId, Client, Source, Timeouts};
use serde_json::Value;

const CH: u32 = 0x120101;

struct Com<'a>(ads::Device<'a>);

impl Com<'_> {
    fn write(&self, offset: u32, data: &[u8]) {
        self.0
            .write(CH, offset, data)
            .unwrap_or_else(|e| panic!("write 0x{offset:X}: {e}"));
    }
    fn u32(&self, offset: u32) -> u32 {
        let mut b = [0u8; 4];
        self.0.read_exact(CH, offset, &mut b).unwrap();
        u32::from_le_bytes(b)
    }
    fn state(&self) -> u32 {
        self.u32(0x109)
    }
    fn wait_state(&self, state: u32) {
        let deadline = Instant::now() + Duration::from_secs(20);
        while self.state() != state {
            assert!(Instant::now() < deadline, "state {state} never came");
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    fn start(&self, program: &str) {
        self.write(0x104, &2i32.to_le_bytes());
        self.write(0x108, format!("{program}\0").as_bytes());
        self.write(0x105, &4i32.to_le_bytes());
    }
    fn string(&self, offset: u32, size: usize) -> String {
        let mut b = vec![0u8; size];
        self.0.read_exact(CH, offset, &mut b).unwrap();
        String::from_utf8_lossy(&b)
            .trim_end_matches('\0')
            .to_string()
    }
}

fn client(served: &ads_common::Served) -> Client {
    Client::new(
        served.server.local_addr(),
        Timeouts::new(Duration::from_secs(5)),
        Source::Addr(AmsAddr::new(AmsNetId::new(10, 1, 2, 3, 1, 1), 40200)),
    )
    .unwrap()
}

fn com_device(c: &Client) -> Com<'_> {
    Com(c.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 553)))
}

fn block_ns(events: &[Value]) -> Vec<u64> {
    ads_common::of(events, "block")
        .iter()
        .filter_map(|e| e["n"].as_u64())
        .collect()
}

const PROGRAM: &str = "N10 G01 X1 F6000\nN20 X2\n/N30 X3\n/2 N40 X4\nN50 X5\nN60 M30\n";

#[test]
fn single_block_runs_one_block_per_start() {
    let params = ads_common::Params::new(1);
    params.program("sb.nc", PROGRAM);
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    com.write(0x01, &[1]);
    let mut b = [0u8; 1];
    com.0.read_exact(CH, 0x03, &mut b).unwrap();
    assert_eq!(b, [1], "mc_active_single_block_r");
    com.start("sb.nc");
    for n in [10u32, 20, 30, 40, 50] {
        com.wait_state(5);
        assert_eq!(com.u32(0x0E), n, "stopped after N{n}");
        assert_eq!(com.string(0x12, 84), "sb.nc", "mc_active_program_name_r");
        // Held: nothing more runs until the next start.
        std::thread::sleep(Duration::from_millis(30));
        assert_eq!(com.u32(0x0E), n);
        assert_eq!(com.state(), 5);
        com.write(0x105, &4i32.to_le_bytes());
    }
    com.wait_state(3);
    drop(c);
    let events = served.finish();
    assert_eq!(block_ns(&events), [10, 20, 30, 40, 50, 60]);
}

#[test]
fn skip_levels_skip_their_blocks_and_single_block_can_be_left() {
    let params = ads_common::Params::new(1);
    params.program("skip.nc", PROGRAM);
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    com.write(0x04, &0x1u32.to_le_bytes()); // skip level 1
    assert_eq!(com.u32(0x05), 1);
    assert_eq!(com.u32(0x06), 1);
    match com.0.write(CH, 0x04, &0x400u32.to_le_bytes()) {
        Err(ads::Error::Ads(_, _, code)) => assert_eq!(code, 0x706, "level 11 does not exist"),
        other => panic!("{other:?}"),
    }
    com.write(0x01, &[1]);
    com.start("skip.nc");
    com.wait_state(5);
    assert_eq!(com.u32(0x0E), 10);
    com.write(0x01, &[0]); // single block off, then one start runs the rest
    com.write(0x137, &[1]);
    com.wait_state(3);
    drop(c);
    let events = served.finish();
    assert_eq!(block_ns(&events), [10, 20, 40, 50, 60]);
}

#[test]
fn block_search_by_number_through_the_com_objects() {
    let params = ads_common::Params::new(1);
    params.program("bs.nc", PROGRAM);
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    com.write(0x49, &4u16.to_le_bytes()); // mc_cmd_bs_type_w: block number
    com.write(0x5F, &50u32.to_le_bytes()); // mc_cmd_bs_block_number_w
    com.write(0x3F, &1i32.to_le_bytes()); // mc_command_execution_mode_w: block search
    let mut t = [0u8; 2];
    com.0.read_exact(CH, 0x61, &mut t).unwrap();
    assert_eq!(
        (u16::from_le_bytes(t), com.u32(0x77), com.u32(0x40)),
        (4, 50, 1)
    );
    assert!(
        com.0.write(CH, 0x3F, &2i32.to_le_bytes()).is_err(),
        "contour visualisation is not modelled"
    );
    com.start("bs.nc");
    com.wait_state(3);
    assert_eq!(com.u32(0x40), 0, "the start took the block search");
    drop(c);
    let events = served.finish();
    let search = ads_common::of(&events, "search");
    assert_eq!(search.len(), 1, "{search:?}");
    assert_eq!(search[0]["found"], true);
    assert_eq!(block_ns(&events).first(), Some(&50));
}

#[test]
fn axis_positions_acs_and_pcs_in_tenth_micrometres() {
    let params = ads_common::Params::new(1);
    let startup = std::fs::read_to_string(params.startup()).unwrap();
    std::fs::write(params.startup(), startup + "zero_offset_list zero.lis\n").unwrap();
    // G54 shifts X by 10 mm (list unit 0.1 µm).
    std::fs::write(
        params.dir.path().join("params/zero.lis"),
        "np_grp[1].achse[0].versch 100000\n",
    )
    .unwrap();
    params.program("g54.nc", "N10 G54 G01 X5 F6000\nN20 X6\nN30 M30\n");
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    com.write(0x01, &[1]);
    com.start("g54.nc");
    com.wait_state(5);
    assert_eq!(com.u32(0x0E), 10);
    let mut b = [0u8; 4];
    com.0.read_exact(0x120200, 0x10000 + 0x02, &mut b).unwrap();
    assert_eq!(i32::from_le_bytes(b), 150_000, "ACS X = 15 mm");
    com.0.read_exact(0x120201, 0x03, &mut b).unwrap();
    assert_eq!(i32::from_le_bytes(b), 150_000);
    com.0.read_exact(CH, 0x10006, &mut b).unwrap();
    assert_eq!(i32::from_le_bytes(b), 50_000, "PCS X = 5 mm");
    let mut hr = [0u8; 8];
    com.0.read_exact(0x120201, 0x30, &mut hr).unwrap();
    assert_eq!(f64::from_le_bytes(hr), 150_000.0);
    assert_eq!(com.string(0x10002, 16), "X", "mc_axis_1_name_r");
    assert_eq!(com.string(0x2D, 84), "zero.lis", "mc_zero_offset_file_r");
    com.write(0x01, &[0]);
    com.write(0x137, &[1]);
    com.wait_state(3);
    drop(c);
    served.finish();
}

#[test]
fn the_active_tool_objects_read_the_tool_list_of_werkz_data() {
    let params = ads_common::Params::new(1);
    let startup = std::fs::read_to_string(params.startup()).unwrap();
    std::fs::write(params.startup(), startup + "werkz_data[0] werkz_d.lis\n").unwrap();
    // TF5200 Tool data: wz[2] valid, radius 2.5 mm (0.1 µm).
    std::fs::write(
        params.dir.path().join("params/werkz_d.lis"),
        "wz[2].gueltig 1\nwz[2].radius 25000\n",
    )
    .unwrap();
    params.program("tool.nc", "N10 D2 G01 X5 F6000\nN20 X6\nN30 M30\n");
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    let geo = c.device(AmsAddr::new(AmsNetId::new(5, 6, 7, 8, 1, 1), 551));
    let radius = || {
        let mut b = [0u8; 8];
        geo.read_exact(0x121301, 0x2C, &mut b).unwrap();
        f64::from_le_bytes(b)
    };
    assert_eq!((com.u32(0x1A), radius()), (0, 0.0), "D0 before the start");
    com.write(0x01, &[1]);
    com.start("tool.nc");
    com.wait_state(5);
    assert_eq!(com.u32(0x0E), 10);
    assert_eq!(com.u32(0x1A), 2, "mc_active_tool_id_basic_r: the active D");
    assert_eq!(radius(), 25_000.0, "Actual tool radius, 0.1 µm");
    let mut id = [0xFFu8; 16];
    com.0.read_exact(CH, 0x19, &mut id).unwrap();
    let mut want = [0u8; 16];
    want[0] = 2;
    assert_eq!(
        id, want,
        "mc_active_tool_id_r: basic 2, no sister or variant"
    );
    assert_eq!(com.u32(0x1B), 0);
    assert_eq!(com.string(0x2F, 84), "werkz_d.lis", "mc_tool_file_r");
    assert_eq!(com.string(0x2D, 84), "", "mc_zero_offset_file_r: no list");
    com.write(0x01, &[0]);
    com.write(0x137, &[1]);
    com.wait_state(3);
    drop(c);
    served.finish();
}

#[test]
fn the_last_msg_text_is_read_at_mc_message_r() {
    let params = ads_common::Params::new(1);
    params.program(
        "msg.nc",
        "N10 #MSG [\"Insert the clamp\"]\nN20 G04 0.5\nN25 P1 = 3.26\n\
         N30 #MSG [\"Clamp %d closed at %.1f mm\", 2, P1]\nN40 M30\n",
    );
    let served = ads_common::Served::start(params);
    let c = client(&served);
    let com = com_device(&c);
    assert_eq!(
        com.string(0x1F, 120),
        "",
        "no message before a program sent one"
    );
    com.start("msg.nc");
    com.wait_state(3);
    // The formatted text (TF5200 "Messages from the NC program": printf-style values).
    assert_eq!(com.string(0x1F, 120), "Clamp 2 closed at 3.3 mm");
    drop(c);
    let events = served.finish();
    let texts: Vec<&str> = ads_common::of(&events, "message")
        .iter()
        .filter_map(|e| e["text"].as_str())
        .collect();
    assert_eq!(texts, ["Insert the clamp", "Clamp 2 closed at 3.3 mm"]);
}

#[test]
fn m00_always_holds_and_m01_only_with_the_m01_switch() {
    let program = "N10 G01 X1 F6000\nN20 M00\nN30 X2\nN40 M01\nN50 X3\nN60 M30\n";
    for switch in [false, true] {
        let params = ads_common::Params::new(1);
        params.program("stops.nc", program);
        let served = ads_common::Served::start(params);
        let c = client(&served);
        let com = com_device(&c);
        com.write(0x07, &[u8::from(switch)]);
        let mut b = [0u8; 1];
        com.0.read_exact(CH, 0x08, &mut b).unwrap();
        assert_eq!(b, [u8::from(switch)], "mc_command_M01_stop_enable_r");
        com.start("stops.nc");
        let stops: &[u32] = if switch { &[20, 40] } else { &[20] };
        for &n in stops {
            com.wait_state(5);
            assert_eq!(com.u32(0x0E), n, "held at N{n}");
            std::thread::sleep(Duration::from_millis(30));
            assert_eq!(com.state(), 5, "still held at N{n}");
            assert_eq!(com.u32(0x0E), n);
            com.write(0x105, &4i32.to_le_bytes());
        }
        com.wait_state(3);
        drop(c);
        let events = served.finish();
        assert_eq!(block_ns(&events), [10, 20, 30, 40, 50, 60]);
        let stop_ms: Vec<u64> = ads_common::of(&events, "program_stop")
            .iter()
            .filter_map(|e| e["m"].as_u64())
            .collect();
        assert_eq!(stop_ms, if switch { vec![0, 1] } else { vec![0] });
    }
}
