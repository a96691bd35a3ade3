//! The channel list's technology parameters (TF5200 "M and H functions": `m_synch`,
//! `h_synch`, process times, pre-outputs, the spindle's and the tool's) read into the channel's
//! `TechnoTable`, and `ncchannel check --params` reporting the M/H functions a program uses
//! that the channel does not define.

use std::path::{Path, PathBuf};
use std::process::Command;

use ncchannel::params::{self, Config, ParamError};
use ncchannel::vocab::techno::{FunctionDef, SyncSpec, SyncType, TechnoTable};
use ncchannel::{Diagnostic, Severity};

/// A start-up list naming one channel list with `channel` as its text, loaded.
struct Loaded {
    _dir: tempfile::TempDir,
    channel: PathBuf,
    result: Result<Config, ParamError>,
}

fn load(channel: &str) -> Loaded {
    let dir = tempfile::tempdir().unwrap();
    let startup = dir.path().join("startup.lis");
    std::fs::write(&startup, "kanal_anzahl 1\nsda_mds[0] ch.lis\n").unwrap();
    let ch = dir.path().join("ch.lis");
    std::fs::write(&ch, channel).unwrap();
    let result = params::load(&startup);
    Loaded {
        _dir: dir,
        channel: ch,
        result,
    }
}

/// The channel's table and the warnings, asserting it loaded.
fn table(channel: &str) -> (TechnoTable, Vec<Diagnostic>) {
    let l = load(channel);
    match l.result {
        Ok(mut c) => (c.channels.remove(0).techno, c.warnings),
        Err(e) => panic!("{e}"),
    }
}

/// The errors of a list that must be refused, with the channel list's path.
fn refused(channel: &str) -> (Vec<Diagnostic>, PathBuf) {
    let l = load(channel);
    match l.result {
        Ok(_) => panic!("loaded: {channel}"),
        Err(e) => (e.errors(), l.channel),
    }
}

fn spec(sync: SyncType, plc_info: bool) -> SyncSpec {
    SyncSpec { sync, plc_info }
}

fn def(sync: SyncType, plc_info: bool, process_time_us: u32, pre_output: u32) -> FunctionDef {
    FunctionDef {
        sync: spec(sync, plc_info),
        process_time_us,
        pre_output,
    }
}

/// The one error of `errs`: at `file:line:col`, with exactly `message`.
fn one_error_at(errs: &[Diagnostic], file: &Path, line: usize, col: usize, message: &str) {
    assert_eq!(errs.len(), 1, "{errs:#?}");
    let d = &errs[0];
    assert_eq!(d.severity, Severity::Error);
    assert_eq!((d.file.as_path(), d.line, d.col), (file, line, col), "{d}");
    assert_eq!(d.message, message);
}

#[test]
fn symbols_values_and_bar_combinations_define_the_functions_sorted_by_number() {
    let (t, warnings) = table(
        "m_synch[20]  MVS_SVS\n\
         m_synch[8]   0x00000002\n\
         m_synch[9]   4\n\
         m_synch[12]  PLC_INFO | MNS_SNS\n\
         m_synch[13]  mvs_slm\n\
         h_synch[7]   MOS\n\
         h_synch[2]   PLC_INFO|MVS_SLP\n\
         h_synch[65535] 0x00020000\n",
    );
    assert!(warnings.is_empty(), "{warnings:#?}");
    let numbers: Vec<u32> = t.m.iter().map(|(n, _)| *n).collect();
    assert_eq!(numbers, [8, 9, 12, 13, 20]);
    let numbers: Vec<u32> = t.h.iter().map(|(n, _)| *n).collect();
    assert_eq!(numbers, [2, 7, 65535]);
    assert_eq!(t.m_def(8), Some(def(SyncType::MvsSvs, false, 0, 0)));
    assert_eq!(t.m_def(9), Some(def(SyncType::MvsSns, false, 0, 0)));
    assert_eq!(t.m_def(12), Some(def(SyncType::MnsSns, true, 0, 0)));
    assert_eq!(t.m_def(13), Some(def(SyncType::MvsSlm, false, 0, 0)));
    assert_eq!(t.m_def(20), Some(def(SyncType::MvsSvs, false, 0, 0)));
    assert_eq!(t.h_def(2), Some(def(SyncType::MvsSlp, true, 0, 0)));
    assert_eq!(t.h_def(7), Some(def(SyncType::Mos, false, 0, 0)));
    // PLC_INFO alone: reported to the PLC without a type of its own.
    assert_eq!(t.h_def(65535), Some(def(SyncType::NoSynch, true, 0, 0)));
    assert!(t.m_def(10).is_none());
    assert!(t.h_def(8).is_none());
    // The kernel's internal M functions stay defined without an entry.
    assert!(t.m_def(30).is_some());
}

#[test]
fn a_second_column_must_say_the_same_as_the_first() {
    // The kernel's own lists: the symbol then the value, or the value then the symbol.
    let (t, warnings) = table(
        "spindel[0].m3_synch     PLC_INFO | MVS_SVS    0x00020002\n\
         m_synch[96]             0x01000000  MEP_SVS\n\
         m_pre_outp[96]          100000     in 0.1 um\n\
         m_synch[8]              MVS_SVS    (coolant on) 0x1\n\
         m_synch[9]              0x00000004 coolant off\n",
    );
    assert!(warnings.is_empty(), "{warnings:#?}");
    assert_eq!(t.m_def(3), Some(def(SyncType::MvsSvs, true, 0, 0)));
    assert_eq!(t.m_def(96), Some(def(SyncType::MepSvs, false, 0, 100_000)));
    // After `(` and after words that are no second column: a comment.
    assert_eq!(t.m_def(8), Some(def(SyncType::MvsSvs, false, 0, 0)));
    assert_eq!(t.m_def(9), Some(def(SyncType::MvsSns, false, 0, 0)));

    let (errs, file) =
        refused("streaming_prog_file s.nc\nm_synch[3]  PLC_INFO | MVS_SVS  0x00000002\n");
    one_error_at(
        &errs,
        &file,
        2,
        33,
        "m_synch[3]: `PLC_INFO | MVS_SVS` is 0x00020002, but the value after it is 0x00000002; \
         the two columns must agree",
    );
    let (errs, file) = refused("h_synch[4] 0x00000001 MVS_SVS\n");
    one_error_at(
        &errs,
        &file,
        1,
        23,
        "h_synch[4]: `0x00000001` is 0x00000001, but `MVS_SVS` after it is 0x00000002; \
         the two columns must agree",
    );
}

#[test]
fn an_unmodelled_type_is_refused_naming_it_at_file_line_and_column() {
    let (errs, file) = refused("streaming_prog_file s.nc\n\nm_synch[25]   MOS_TS\n");
    one_error_at(
        &errs,
        &file,
        3,
        15,
        "m_synch[25]: MOS_TS is a synchronisation type ncchannel does not model",
    );
    // Inside a combination, the column is the symbol's.
    let (errs, file) = refused("spindel[0].s_synch  PLC_INFO | FAW_SYNCH\n");
    one_error_at(
        &errs,
        &file,
        1,
        32,
        "spindel[0].s_synch: FAW_SYNCH is a synchronisation type ncchannel does not model",
    );
    // By value: MNE_SNS is 0x20.
    let (errs, file) = refused("tool.synch 0x00000020\n");
    one_error_at(
        &errs,
        &file,
        1,
        12,
        "tool.synch: MNE_SNS is a synchronisation type ncchannel does not model",
    );
}

#[test]
fn unknown_symbols_values_and_two_types_are_errors() {
    let (errs, file) = refused("h_synch[1]  MVS_FOO\n");
    assert_eq!(errs.len(), 1, "{errs:#?}");
    assert_eq!(
        (errs[0].file.as_path(), errs[0].line, errs[0].col),
        (file.as_path(), 1, 13)
    );
    assert!(
        errs[0]
            .message
            .starts_with("h_synch[1]: `MVS_FOO` is not a synchronisation type (NO_SYNCH, MOS,"),
        "{}",
        errs[0].message
    );
    let (errs, _) = refused("m_synch[1]  0x00000040\n");
    assert_eq!(errs.len(), 1, "{errs:#?}");
    assert!(
        errs[0]
            .message
            .starts_with("m_synch[1]: 0x00000040 is not a synchronisation type ncchannel models"),
        "{}",
        errs[0].message
    );
    let (errs, _) = refused("m_synch[1]  MOS | MVS_SVS\n");
    assert_eq!(errs.len(), 1, "{errs:#?}");
    assert_eq!(
        errs[0].message,
        "m_synch[1]: MOS and MVS_SVS: two synchronisation types for one function"
    );
    let (errs, _) = refused("m_synch[1]  \"MOS\"\nm_synch[2] 1.5\n");
    assert_eq!(errs.len(), 2, "{errs:#?}");
    // Every bad entry in one run, each at its own line.
    assert_eq!((errs[0].line, errs[1].line), (1, 2));
}

#[test]
fn process_times_and_pre_outputs_join_their_functions() {
    let (t, warnings) = table(
        "m_synch[8]          MVS_SVS\n\
         m_prozess_zeit[8]   100000\n\
         h_synch[3]          MVS_SNS\n\
         h_prozess_zeit[3]   0x10\n\
         m_synch[97]         MET_SVS\n\
         m_pre_outp[97]      40000\n\
         m_prozess_zeit[97]  5000\n\
         m_prozess_zeit[7]   2000\n\
         m_synch[11]         MVS_SVS\n\
         m_pre_outp[11]      250000\n\
         m_synch[95]         MEP_SVS\n",
    );
    assert_eq!(t.m_def(8), Some(def(SyncType::MvsSvs, false, 100_000, 0)));
    assert_eq!(t.h_def(3), Some(def(SyncType::MvsSns, false, 16, 0)));
    assert_eq!(
        t.m_def(97),
        Some(def(SyncType::MetSvs, false, 5000, 40_000))
    );
    // A process time without a type: the function stays undefined.
    assert!(t.m_def(7).is_none());
    // A pre-output for a type that does not pre-output: not used.
    assert_eq!(t.m_def(11), Some(def(SyncType::MvsSvs, false, 0, 0)));
    // MEP_SVS without one: output at the synchronisation point (P-CHAN-00070's default 0).
    assert_eq!(t.m_def(95), Some(def(SyncType::MepSvs, false, 0, 0)));
    let lines: Vec<(usize, usize)> = warnings.iter().map(|w| (w.line, w.col)).collect();
    assert_eq!(warnings.len(), 3, "{warnings:#?}");
    assert!(warnings.iter().all(|w| w.severity == Severity::Warning));
    let find = |line: usize| {
        warnings
            .iter()
            .find(|w| w.line == line)
            .unwrap_or_else(|| panic!("no warning on line {line}: {lines:?}"))
    };
    assert_eq!(
        find(8).message,
        "m_prozess_zeit[7] without m_synch[7]: M7 stays undefined; not used"
    );
    assert!(find(10)
        .message
        .starts_with("m_pre_outp[11]: M11 is MVS_SVS;"));
    assert!(find(11)
        .message
        .starts_with("m_synch[95]: MEP_SVS without a pre-output"));

    let (errs, file) = refused("m_synch[8] MOS\nm_prozess_zeit[8] -5\n");
    assert_eq!(errs.len(), 1, "{errs:#?}");
    assert_eq!(
        (errs[0].file.as_path(), errs[0].line, errs[0].col),
        (file.as_path(), 2, 19)
    );
    let (errs, _) = refused("m_synch[8] MOS\nm_prozess_zeit[8] 4294967296\n");
    assert!(errs[0].message.contains("m_prozess_zeit[8]"), "{errs:#?}");
}

#[test]
fn the_spindle_and_the_tool() {
    let (t, warnings) = table(
        "spindel[0].bezeichnung      S1\n\
         spindel[0].log_achs_nr      6\n\
         spindel[0].s_synch          MOS                   0x00000001\n\
         spindel[0].m3_synch         PLC_INFO | MVS_SVS    0x00020002\n\
         spindel[0].m4_synch         PLC_INFO | MVS_SNS    0x00020004\n\
         spindel[0].m5_synch         PLC_INFO | MVS_SVS    0x00020002\n\
         spindel[0].m19_synch        MNS_SNS               0x00000008\n\
         spindel[0].s_prozess_zeit   1000000\n\
         spindel[0].m3_prozess_zeit  1000000\n\
         spindel[0].m4_prozess_zeit  1000000\n\
         spindel[0].m5_prozess_zeit  1500000\n\
         spindel[0].m19_prozess_zeit 2000000\n\
         tool.synch                  MNS_SNS 0x00000008\n\
         tool.prozess_zeit           300000\n",
    );
    assert!(warnings.is_empty(), "{warnings:#?}");
    assert_eq!(t.s, def(SyncType::Mos, false, 1_000_000, 0));
    assert_eq!(
        t.spindle_m,
        [
            (3, def(SyncType::MvsSvs, true, 1_000_000, 0)),
            (4, def(SyncType::MvsSns, true, 1_000_000, 0)),
            (5, def(SyncType::MvsSvs, true, 1_500_000, 0)),
            (19, def(SyncType::MnsSns, false, 2_000_000, 0)),
        ]
    );
    assert_eq!(
        t.m_def(19),
        Some(def(SyncType::MnsSns, false, 2_000_000, 0))
    );
    assert_eq!(t.t, def(SyncType::MnsSns, false, 300_000, 0));
    assert!(t.m.is_empty());

    // Another spindle: not modelled, said so, and the table keeps spindle 0's.
    let l = load("spindel[1].m3_synch  MVS_SVS\nspindel[1].bezeichnung S2\n");
    let c = l.result.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(c.warnings.len(), 1, "{:#?}", c.warnings);
    let w = &c.warnings[0];
    assert_eq!(
        (w.file.as_path(), w.line, w.col),
        (l.channel.as_path(), 1, 1)
    );
    assert_eq!(
        w.message,
        "spindel[1].m3_synch: only spindle 0 is modelled; not read"
    );
    assert_eq!(c.channels[0].techno, TechnoTable::kernel_defaults());
}

#[test]
fn the_spindle_entry_wins_over_m_synch_for_its_functions() {
    let l = load(
        "m_synch[3]                MOS\n\
         m_prozess_zeit[3]         5\n\
         spindel[0].m3_synch       MVS_SVS\n\
         m_synch[19]               MOS\n\
         m_synch[6]                MOS\n",
    );
    let c = l.result.unwrap_or_else(|e| panic!("{e}"));
    let t = &c.channels[0].techno;
    assert_eq!(t.m_def(3), Some(def(SyncType::MvsSvs, false, 0, 0)));
    // Without a spindel[0].m19_synch, M19 is the spindle's default (NO_SYNCH), not MOS.
    assert_eq!(t.m_def(19), Some(def(SyncType::NoSynch, false, 0, 0)));
    assert_eq!(t.m_def(6), Some(def(SyncType::Mos, false, 0, 0)));
    let mut lines: Vec<usize> = c.warnings.iter().map(|w| w.line).collect();
    lines.sort_unstable();
    assert_eq!(lines, [1, 2, 4], "{:#?}", c.warnings);
    for w in &c.warnings {
        assert_eq!(w.severity, Severity::Warning);
        assert_eq!(w.file, l.channel);
        assert!(w.message.contains("is a spindle function"), "{w}");
    }
    assert!(
        c.warnings[0].message.contains("spindel[0].m"),
        "{}",
        c.warnings[0]
    );
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `ncchannel check` with `args` in the repository: exit code and stdout.
fn check(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

/// Each shipped start-up list with the programs its channels run.
const SHIPPED: [(&str, &str); 4] = [
    ("params/startup.lis", "nc"),
    ("params/soak/startup.lis", "params/soak/nc"),
    ("params/soak/startup4.lis", "params/soak/nc"),
    (
        "params/installation/listen/hochlauf.lis",
        "params/installation/prg",
    ),
];

#[test]
fn the_shipped_lists_load_and_define_the_functions_their_programs_use() {
    for (startup, programs) in SHIPPED {
        let cfg = params::load(&root().join(startup)).unwrap_or_else(|e| panic!("{startup}: {e}"));
        assert!(cfg.warnings.is_empty(), "{startup}: {:#?}", cfg.warnings);
        for (i, ch) in cfg.channels.iter().enumerate() {
            let channel = (i + 1).to_string();
            let (code, out) = check(&["--params", startup, "--channel", &channel, programs]);
            assert_eq!(code, 0, "{startup} channel {channel}: {out}");
            // The soak's generated programs switch coolant with M08 / M09.
            if startup.starts_with("params/soak") {
                assert!(ch.techno.m_def(8).is_some() && ch.techno.m_def(9).is_some());
            }
        }
    }
    // The shipped channel 1: coolant, laser, spindle and tool as its comments say.
    let cfg = params::load(&root().join("params/startup.lis")).unwrap();
    let t = &cfg.channels[0].techno;
    assert_eq!(t.m_def(8), Some(def(SyncType::MvsSvs, false, 100_000, 0)));
    assert_eq!(t.m_def(9), Some(def(SyncType::MvsSns, false, 50_000, 0)));
    assert!(t.m_def(10).is_some() && t.m_def(11).is_some());
    assert_eq!(t.m_def(3), Some(def(SyncType::MvsSvs, true, 500_000, 0)));
    assert_eq!(t.t.sync, spec(SyncType::MvsSvs, false));
}

#[test]
fn check_reports_an_undefined_m_and_h_with_their_ids_and_places() {
    let dir = tempfile::tempdir().unwrap();
    let prog = dir.path().join("p.nc");
    std::fs::write(
        &prog,
        "N10 G01 X10 F100 M77\n\
         #COMMENT BEGIN\n\
         M78 is commented out\n\
         #COMMENT END\n\
         N20 X20 \\\n  H5 M8\n\
         N30 H7=12 M77\n\
         N40 M3 M30\n\
         N50 M1001\n",
    )
    .unwrap();
    let p = prog.to_str().unwrap();
    let (code, out) = check(&["--params", "params/startup.lis", p]);
    assert_eq!(code, 1, "{out}");
    let findings: Vec<&str> = out.lines().filter(|l| l.contains(": error")).collect();
    assert_eq!(
        findings,
        [
            format!("{p}:1:18: error 20157: M77 is not defined in the channel's parameters (m_synch[77] missing) (used 2 times, first here)"),
            format!("{p}:6:3: error 20162: H5 is not defined in the channel's parameters (h_synch[5] missing)"),
            format!("{p}:7:5: error 20162: H7 is not defined in the channel's parameters (h_synch[7] missing)"),
            // Above M999 the kernel looks for an internal M function (TF5200 diagnosis 20160).
            format!("{p}:9:5: error 20160: M1001 is not defined in the channel's parameters (m_synch[1001] missing)"),
        ],
        "{out}"
    );
    // A channel list alone does as well; without --params, M/H numbers are not checked.
    let (code, out) = check(&["--params", "params/channel1.lis", p]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains(&format!("{p}:1:18: error 20157")), "{out}");
    let (code, out) = check(&[p]);
    assert_eq!(code, 0, "{out}");
    // A channel the start-up list does not have: said, and the exit is 1.
    let (code, out) = check(&["--params", "params/startup.lis", "--channel", "2", p]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("--channel 2: the start-up list has 1 channel(s)"),
        "{out}"
    );
}
