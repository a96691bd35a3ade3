//! V.E. variables declared by a list of external variables (start-up list `ve_var[i]`,
//! TF5200 P-STUP-00146), read and written by name over a real ADS socket on the SDA port
//! (552, decoder group `0x122300 + ch`): members and indices as a program writes them, each
//! value in the PLC type of its declared type (SGN16 → INT, BOOLEAN → BOOL, REAL64 → LREAL,
//! STRING → STRING(127), NUL-padded), a value outside the type refused, an undeclared name
//! not found.

use std::time::Duration;

use crate::support::ads::*;
use ncchannel::ads::client::{AdsClient, ClientError};

const DECODER: u32 = 0x122301;
const HANDLE_BY_NAME: u32 = 0x46;
const READ_BY_NAME: u32 = 0x48;
const WRITE_BY_NAME: u32 = 0x4A;

/// A client of the SDA port (552), where V.E. variables are read and written by name.
fn connect(served: &Served) -> AdsClient {
    super::ads_model_objects::connect(served, 552)
}

fn refused(r: Result<impl std::fmt::Debug, ClientError>) -> u32 {
    match r {
        Err(e) => e.ads_result().map(|r| r.0).unwrap_or_else(|| panic!("{e}")),
        Ok(v) => panic!("accepted: {v:?}"),
    }
}

/// `name` NUL value: the write-by-name payload.
fn named(name: &str, value: &[u8]) -> Vec<u8> {
    [name.as_bytes(), &[0], value].concat()
}

fn read(sda: &mut AdsClient, name: &str, length: u32) -> Vec<u8> {
    sda.read_write(
        DECODER,
        READ_BY_NAME,
        length,
        format!("{name}\0").as_bytes(),
    )
    .unwrap()
}

/// One channel whose start-up list names the fixture V.E. list (`ve_var[0]`).
fn params_with_list() -> Params {
    let params = Params::new(1);
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ext_vars/ve.lis"),
        params.dir.path().join("params/ve.lis"),
    )
    .unwrap();
    let startup = std::fs::read_to_string(params.startup()).unwrap();
    std::fs::write(params.startup(), format!("{startup}ve_var[0] ve.lis\n")).unwrap();
    params
}

#[test]
fn declared_variables_are_read_and_written_by_name_in_their_types() {
    let served = Served::start(params_with_list());
    let mut sda = connect(&served);

    // SGN16 → INT, two bytes, signed.
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.COUNT", &(-7i16).to_le_bytes()),
    )
    .unwrap();
    assert_eq!(read(&mut sda, "V.E.count", 2), (-7i16).to_le_bytes());
    // A structure member and an array element, any case.
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.Sch.Preflow", &2.5f64.to_le_bytes()),
    )
    .unwrap();
    assert_eq!(read(&mut sda, "V.E.SCH.PREFLOW", 8), 2.5f64.to_le_bytes());
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.FARBE[2]", &513u16.to_le_bytes()),
    )
    .unwrap();
    assert_eq!(read(&mut sda, "V.E.FARBE[2]", 2), 513u16.to_le_bytes());
    assert_eq!(read(&mut sda, "V.E.FARBE[0]", 2), [0, 0], "starts at 0");
    // READ_ONLY binds NC programs only (P-EXTV-00006): the PLC side writes it.
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.USERINTERACTION.PLC_READY", &[1]),
    )
    .unwrap();
    assert_eq!(read(&mut sda, "V.E.USERINTERACTION.PLC_READY", 1), [1]);
    // A STRING member: 127 characters and the NUL, padded.
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.USERINTERACTION.MESSAGE", b"Insert tool 4\0"),
    )
    .unwrap();
    let text = read(&mut sda, "V.E.USERINTERACTION.MESSAGE", 128);
    assert_eq!(text.len(), 128);
    assert_eq!(&text[..14], b"Insert tool 4\0");
    assert!(text[14..].iter().all(|&b| b == 0));
    // By handle too: the same bytes.
    let h = u32_at(
        &sda.read_write(DECODER, HANDLE_BY_NAME, 4, b"V.E.FARBE[2]")
            .unwrap(),
        0,
    );
    assert_eq!(sda.read(DECODER, h, 2).unwrap(), 513u16.to_le_bytes());

    // Refusals: outside the type (a BOOL of 2), the wrong size, an index outside the
    // array, a name the list does not declare.
    assert_eq!(
        refused(sda.write(DECODER, WRITE_BY_NAME, &named("V.E.LAMP", &[2]))),
        0x706
    );
    assert_eq!(
        refused(sda.write(DECODER, WRITE_BY_NAME, &named("V.E.COUNT", &[1, 0, 0, 0]))),
        0x705
    );
    assert_eq!(
        refused(sda.read_write(DECODER, READ_BY_NAME, 2, b"V.E.FARBE[3]\0")),
        0x70C
    );
    assert_eq!(
        refused(sda.read_write(DECODER, HANDLE_BY_NAME, 4, b"V.E.UNDECLARED")),
        0x70C
    );
    assert_eq!(
        refused(sda.write(
            DECODER,
            WRITE_BY_NAME,
            &named("V.E.UNDECLARED", &1f64.to_le_bytes())
        )),
        0x70C,
        "with a list, a write makes no variable"
    );
    served.finish();
}

/// A program sees what the PLC side wrote, and the PLC side what the program wrote.
#[test]
fn a_program_and_the_ads_side_share_the_variables() {
    let params = params_with_list();
    params.program(
        "share.nc",
        "%share\nN10 V.E.UserInteraction.Message = V.E.TEACH_FILE_NAME + \" done\"\n\
         N20 V.E.COUNT = V.E.COUNT + 1\nM30\n",
    );
    let served = Served::start(params);
    let mut sda = connect(&served);
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.TEACH_FILE_NAME", b"teach_01.nc\0"),
    )
    .unwrap();
    sda.write(
        DECODER,
        WRITE_BY_NAME,
        &named("V.E.COUNT", &41i16.to_le_bytes()),
    )
    .unwrap();
    served
        .channels
        .command(1, ncchannel::machine::Op::Start("share.nc".into()));
    served.channels.wait_for(1, Duration::from_secs(20), |s| {
        s.state == ncchannel::channel::State::Ready && s.program.is_none() && s.blocks > 0
    });
    assert_eq!(read(&mut sda, "V.E.COUNT", 2), 42i16.to_le_bytes());
    let text = read(&mut sda, "V.E.USERINTERACTION.MESSAGE", 128);
    assert_eq!(&text[..17], b"teach_01.nc done\0");
    served.finish();
}
