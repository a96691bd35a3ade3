//! The splitter against the rules of SINUMERIK Manage MyPrograms, fed in chunks
//! of every size: same files whatever the chunking.

use ncchannel::dnc::{
    Anchor, Markers, ProgramEnd, ProgramSink, ProgramStart, SplitSummary, Splitter, LINE_WINDOW,
};
use proptest::prelude::*;

#[derive(Debug, Clone, PartialEq)]
struct Prog {
    data: Vec<u8>,
    complete: bool,
    /// (workpiece dir, file name) from the name lines.
    name: Option<(Option<String>, String)>,
    lines: (u64, u64),
}

#[derive(Default)]
struct Collect {
    progs: Vec<Prog>,
    cur: Option<Vec<u8>>,
}

impl ProgramSink for Collect {
    type Error = std::convert::Infallible;
    fn start(&mut self, _s: &ProgramStart) -> Result<(), Self::Error> {
        assert!(self.cur.is_none(), "start inside a program");
        self.cur = Some(Vec::new());
        Ok(())
    }
    fn data(&mut self, b: &[u8]) -> Result<(), Self::Error> {
        self.cur
            .as_mut()
            .expect("data outside a program")
            .extend_from_slice(b);
        Ok(())
    }
    fn end(&mut self, e: ProgramEnd) -> Result<(), Self::Error> {
        let data = self.cur.take().expect("end outside a program");
        assert_eq!(data.len() as u64, e.bytes);
        self.progs.push(Prog {
            data,
            complete: e.complete,
            name: e.name.file_name(),
            lines: (e.first_line, e.last_line),
        });
        Ok(())
    }
}

fn markers(start: &[&str], end: &[&str]) -> Markers {
    Markers::new(start, end, Anchor::Anywhere).unwrap()
}

/// Split `input` fed in chunks of `chunk` bytes (0: all at once).
fn split_chunked(m: &Markers, input: &[u8], chunk: usize) -> (Vec<Prog>, SplitSummary) {
    let mut s = Splitter::new(m.clone());
    let mut c = Collect::default();
    if chunk == 0 {
        s.feed(input, &mut c).unwrap();
    } else {
        for piece in input.chunks(chunk) {
            s.feed(piece, &mut c).unwrap();
        }
    }
    let sum = s.finish(&mut c).unwrap();
    assert!(c.cur.is_none());
    (c.progs, sum)
}

/// Split and check that every chunk size from 1 to 64 gives the same programs.
fn split(m: &Markers, input: &str) -> (Vec<Prog>, SplitSummary) {
    let whole = split_chunked(m, input.as_bytes(), 0);
    for chunk in 1..=64 {
        let (p, s) = split_chunked(m, input.as_bytes(), chunk);
        assert_eq!(p, whole.0, "chunk size {chunk}");
        assert_eq!(s, whole.1, "chunk size {chunk}");
    }
    whole
}

fn texts(p: &[Prog]) -> Vec<String> {
    p.iter()
        .map(|p| String::from_utf8(p.data.clone()).unwrap())
        .collect()
}

#[test]
fn start_only_ignores_data_before_the_first_start_and_runs_to_the_next_start() {
    let m = markers(&["%"], &[]);
    let (p, s) = split(&m, "header\nN1 X1\n%P1\nN10 G0\nN20 M30\n%P2\nN10 G1\n");
    assert_eq!(texts(&p), ["%P1\nN10 G0\nN20 M30\n", "%P2\nN10 G1\n"]);
    assert!(
        p.iter().all(|p| p.complete),
        "start-only: the last one runs to the data end"
    );
    assert_eq!(p[0].lines, (3, 5));
    assert_eq!(p[1].name, Some((None, "P2.nc".into())));
    assert_eq!(s.bytes_ignored, "header\nN1 X1\n".len() as u64);
    assert!(!s.no_start_marker());
}

#[test]
fn start_only_without_a_start_discards_everything() {
    let m = markers(&["%", "START"], &[]);
    let (p, s) = split(&m, "N10 G0 X1\nN20 M30\n");
    assert!(p.is_empty());
    assert!(s.no_start_marker());
    assert_eq!(s.bytes_ignored, s.bytes_in);
}

#[test]
fn end_only_saves_up_to_each_end_and_the_last_block_without_one() {
    let m = markers(&[], &["M30", "M02"]);
    let (p, _) = split(&m, "N1 G0\nN2 M30\nN1 G1\nN2 M02\nN1 G2\nN2 X5\n");
    assert_eq!(
        texts(&p),
        ["N1 G0\nN2 M30\n", "N1 G1\nN2 M02\n", "N1 G2\nN2 X5\n"]
    );
    assert!(p.iter().all(|p| p.complete));
    // No end marker at all: the whole data is one file.
    let (p, _) = split(&m, "A\nB\nC");
    assert_eq!(texts(&p), ["A\nB\nC"]);
    // Line ends after the last end make no empty program.
    let (p, s) = split(&m, "A\nM30\n\r\n\n");
    assert_eq!(texts(&p), ["A\nM30\n"]);
    assert_eq!(s.bytes_ignored, 3);
}

#[test]
fn start_and_end_keeps_regions_and_ignores_what_lies_between() {
    let m = markers(&["%"], &["M30"]);
    let input =
        "noise\n%P1\nN10 G0\n%NOT_A_START\nN20 M30\nbetween\nM30 outside\n%P2\nN10 M30\ntail\n";
    let (p, s) = split(&m, input);
    assert_eq!(
        texts(&p),
        ["%P1\nN10 G0\n%NOT_A_START\nN20 M30\n", "%P2\nN10 M30\n"]
    );
    assert!(p.iter().all(|p| p.complete));
    assert_eq!(p[0].name, Some((None, "P1.nc".into())), "first %name wins");
    assert_eq!(
        s.bytes_ignored,
        ("noise\n".len() + "between\nM30 outside\n".len() + "tail\n".len()) as u64
    );
}

#[test]
fn start_and_end_alternate_even_with_the_same_string() {
    // Tape style: a program between two `%` lines. After a start only ends are searched,
    // from the next line on.
    let m = markers(&["%"], &["%"]);
    let (p, _) = split(&m, "%\nN1\nN2\n%\nx\n%\nN3\n%\n");
    assert_eq!(texts(&p), ["%\nN1\nN2\n%\n", "%\nN3\n%\n"]);
}

#[test]
fn any_of_three_start_and_three_end_strings() {
    let m = markers(&["BEGIN", "%", "START"], &["M30", "M02", "M17"]);
    let (p, _) = split(&m, "START a\nM17\nx\nBEGIN b\nM02\ny\n%c\nN5 M30\n");
    assert_eq!(
        texts(&p),
        ["START a\nM17\n", "BEGIN b\nM02\n", "%c\nN5 M30\n"]
    );
}

#[test]
fn markers_anywhere_or_only_at_the_line_start() {
    let anywhere = markers(&[], &["M30"]);
    let (p, _) = split(&anywhere, "N1\nN2 M30\nN3\n");
    assert_eq!(texts(&p), ["N1\nN2 M30\n", "N3\n"]);
    let at_start = Markers::new(Vec::<&str>::new(), ["M30"], Anchor::LineStart).unwrap();
    let (p, _) = split(&at_start, "N1\nN2 M30\nM30\nN3\n");
    assert_eq!(texts(&p), ["N1\nN2 M30\nM30\n", "N3\n"]);
}

#[test]
fn a_cut_off_region_is_marked_incomplete() {
    let m = markers(&["%"], &["M30"]);
    let (p, s) = split(&m, "%P1\nN1\nM30\n%P2\nN1 G0 X");
    assert_eq!(texts(&p), ["%P1\nN1\nM30\n", "%P2\nN1 G0 X"]);
    assert!(p[0].complete);
    assert!(!p[1].complete);
    assert_eq!(s.cut_off, 1);
}

#[test]
fn abort_makes_any_open_program_incomplete() {
    let m = markers(&[], &["M30"]);
    let mut s = Splitter::new(m);
    let mut c = Collect::default();
    s.feed(b"N1\nM30\nN2\nN3", &mut c).unwrap();
    let sum = s.abort(&mut c).unwrap();
    assert_eq!(texts(&c.progs), ["N1\nM30\n", "N2\nN3"]);
    assert!(c.progs[0].complete);
    assert!(!c.progs[1].complete);
    assert_eq!(sum.cut_off, 1);
    // The machine is reset for the next transfer.
    s.feed(b"N9\nM30\n", &mut c).unwrap();
    let sum = s.finish(&mut c).unwrap();
    assert_eq!(sum.programs, 1);
    assert_eq!(c.progs[2].lines, (1, 2));
}

#[test]
fn line_ends_are_kept_byte_exact() {
    let m = markers(&["%"], &["M30"]);
    let input = "%A\r\nN1 G0\r\nN2\nN3 M30\r\nx\r\n%B\nM30";
    let (p, _) = split(&m, input);
    assert_eq!(texts(&p), ["%A\r\nN1 G0\r\nN2\nN3 M30\r\n", "%B\nM30"]);
    assert!(
        p[1].complete,
        "an end line without a line end still ends the region"
    );
}

/// An archive as a SINUMERIK control sends it: each file opens with `%_N_<NAME>_<TYPE>` and a
/// `;$PATH=` line; main programs end with M30, subprograms with M17 or RET.
const ARCHIVE: &str = "\
%_N_SHAFT_MPF\r
;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r
N10 G0 X0 Z0\r
N20 L CONTOUR\r
N30 M30\r
%_N_CONTOUR_SPF\r
;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r
N10 G1 X10\r
N20 RET\r
%_N_FLANGE_MPF\r
;$PATH=/_N_WKS_DIR/_N_FLANGE_WPD\r
N10 M30\r
%_N_TOOLCHANGE_SPF\r
;$PATH=/_N_SPF_DIR\r
N10 T1 M6\r
N20 M17\r
%_N_MAIN_MPF\r
;$PATH=/_N_MPF_DIR\r
N10 G0 X1\r
N20 M30\r
";

fn names(p: &[Prog]) -> Vec<String> {
    p.iter()
        .map(|p| match &p.name {
            Some((Some(d), f)) => format!("{d}/{f}"),
            Some((None, f)) => f.clone(),
            None => "-".into(),
        })
        .collect()
}

#[test]
fn sinumerik_archive_control_lines_name_and_split_programs() {
    let expected = [
        "SHAFT.wpd/SHAFT.mpf",
        "SHAFT.wpd/CONTOUR.spf",
        "FLANGE.wpd/FLANGE.mpf",
        "TOOLCHANGE.spf",
        "MAIN.mpf",
    ];
    // No markers: only the control lines split.
    let (p, _) = split(&markers(&[], &[]), ARCHIVE);
    assert_eq!(names(&p), expected);
    assert_eq!(texts(&p).concat(), ARCHIVE, "nothing lost, nothing added");
    // End marker M30 only: the subprogram ending in RET is split off by the next `%_N_` line.
    let (p, _) = split(&markers(&[], &["M30"]), ARCHIVE);
    assert_eq!(names(&p), expected);
    // Start `%_N_` and end M30/M17/RET: every file is its own region.
    let (p, _) = split(&markers(&["%_N_"], &["M30", "M17", "RET"]), ARCHIVE);
    assert_eq!(names(&p), expected);
    assert_eq!(
        texts(&p)[1],
        "%_N_CONTOUR_SPF\r\n;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r\nN10 G1 X10\r\nN20 RET\r\n"
    );
    // Start-only on `%`: the same files.
    let (p, _) = split(&markers(&["%"], &[]), ARCHIVE);
    assert_eq!(names(&p), expected);
}

#[test]
fn a_refused_sinumerik_name_is_never_merged_into_the_next_program() {
    // An umlaut, a blank and an over-long name are refused; each program still ends where the
    // next `%_N_` line begins and falls back to a numbered name.
    let long = "A".repeat(101);
    for bad in ["WELLE_\u{c4}", "WEL LE", long.as_str()] {
        let input =
            format!("%_N_{bad}_MPF\r\nN10 G1 X1\r\nM30\r\n%_N_PART2_MPF\r\nN10 G1 X2\r\nM30\r\n");
        for m in [markers(&[], &[]), markers(&["%_N_"], &[])] {
            let (p, _) = split(&m, &input);
            assert_eq!(names(&p), ["-", "PART2.mpf"], "{bad:?}");
            assert_eq!(texts(&p)[1], "%_N_PART2_MPF\r\nN10 G1 X2\r\nM30\r\n");
            assert_eq!(texts(&p).concat(), input, "nothing lost, nothing added");
        }
    }
}

#[test]
fn unnamed_programs_have_no_name() {
    let (p, _) = split(&markers(&[], &["M30"]), "N1\nM30\n%\nN2\nM30\n");
    assert_eq!(names(&p), ["-", "-"]);
}

#[test]
fn a_line_longer_than_the_window_streams_through_and_hides_late_markers() {
    let m = markers(&["%"], &["M30"]);
    let mut input = Vec::new();
    input.extend_from_slice(b"%P\n");
    // A comment line far longer than the window with M30 beyond it: not an end.
    input.push(b';');
    input.extend(std::iter::repeat_n(b'x', LINE_WINDOW + 1000));
    input.extend_from_slice(b" M30\n");
    input.extend_from_slice(b"N1 M30\n");
    input.extend_from_slice(b"skipped\n");
    let whole = split_chunked(&m, &input, 0);
    for chunk in [
        1,
        2,
        7,
        1000,
        4096,
        LINE_WINDOW - 1,
        LINE_WINDOW,
        LINE_WINDOW + 1,
    ] {
        assert_eq!(split_chunked(&m, &input, chunk), whole, "chunk {chunk}");
    }
    let (p, _) = whole;
    assert_eq!(p.len(), 1);
    assert_eq!(p[0].data, input[..input.len() - b"skipped\n".len()]);
    assert_eq!(p[0].lines, (1, 3));
}

#[test]
fn a_marker_early_in_a_long_line_still_counts() {
    let m = markers(&["%"], &["M30"]);
    let mut input = b"%P\nN1 M30 ".to_vec();
    input.extend(std::iter::repeat_n(b'y', 3 * LINE_WINDOW));
    input.extend_from_slice(b"\nafter\n");
    for chunk in [0, 1, 13, 65536] {
        let (p, s) = split_chunked(&m, &input, chunk);
        assert_eq!(p.len(), 1, "chunk {chunk}");
        assert!(p[0].complete);
        assert_eq!(p[0].data.len(), input.len() - b"after\n".len());
        assert_eq!(s.bytes_ignored, 6);
    }
}

/// A line-at-a-time model of the rules, written as plainly as possible.
fn oracle(m: &Markers, start: &[&str], end: &[&str], input: &[u8]) -> Vec<(Vec<u8>, bool)> {
    let has = |l: &[u8], set: &[&str]| {
        set.iter()
            .any(|s| l.windows(s.len()).any(|w| w == s.as_bytes()))
    };
    let blank = |l: &[u8]| l.iter().all(|b| b" \t\r\n\x0c\0\x1a".contains(b));
    let mut out: Vec<(Vec<u8>, bool)> = Vec::new();
    let mut cur: Option<(Vec<u8>, bool)> = None; // (data, named by %_N_)
    let mode = m.mode();
    for line in input.split_inclusive(|&b| b == b'\n') {
        use ncchannel::dnc::Mode::*;
        let sin = line.starts_with(b"%_N_");
        let split = |cur: &mut Option<(Vec<u8>, bool)>, out: &mut Vec<(Vec<u8>, bool)>| {
            if sin && cur.as_ref().is_some_and(|c| c.1) {
                out.push((cur.take().unwrap().0, true));
                *cur = Some((Vec::new(), false));
            }
        };
        match mode {
            StartOnly => {
                if has(line, start) {
                    if let Some(c) = cur.take() {
                        out.push((c.0, true));
                    }
                    cur = Some((Vec::new(), false));
                } else {
                    split(&mut cur, &mut out);
                }
            }
            EndOnly => {
                if cur.is_none() {
                    if blank(line) {
                        continue;
                    }
                    cur = Some((Vec::new(), false));
                } else {
                    split(&mut cur, &mut out);
                }
            }
            StartEnd => {
                if cur.is_none() {
                    if has(line, start) {
                        cur = Some((Vec::new(), false));
                        let c = cur.as_mut().unwrap();
                        c.0.extend_from_slice(line);
                        c.1 |= sin;
                    }
                    continue;
                }
                split(&mut cur, &mut out);
            }
        }
        if let Some(c) = cur.as_mut() {
            c.0.extend_from_slice(line);
            c.1 |= sin;
            if mode != StartOnly && has(line, end) {
                out.push((cur.take().unwrap().0, true));
            }
        }
    }
    if let Some(c) = cur {
        out.push((c.0, mode != ncchannel::dnc::Mode::StartEnd));
    }
    out
}

fn line_strategy() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("%".to_string()),
        Just("%_N_A_MPF".to_string()),
        Just("%_N_B_SPF".to_string()),
        Just(";$PATH=/_N_WKS_DIR/_N_W_WPD".to_string()),
        Just("N10 M30".to_string()),
        Just("M17".to_string()),
        Just("".to_string()),
        "[A-Z0-9 %]{0,12}",
    ]
    .prop_flat_map(|l| prop_oneof![Just(format!("{l}\n")), Just(format!("{l}\r\n"))])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn any_chunking_matches_the_line_model(
        lines in prop::collection::vec(line_strategy(), 0..40),
        cut in any::<bool>(),
        chunk in 1usize..80,
        which in 0usize..4,
    ) {
        let (start, end): (&[&str], &[&str]) = match which {
            0 => (&["%"], &[]),
            1 => (&[], &["M30", "M17"]),
            2 => (&["%"], &["M30", "M17"]),
            _ => (&[], &[]),
        };
        let m = markers(start, end);
        let mut input = lines.concat().into_bytes();
        if cut && !input.is_empty() {
            input.pop();
        }
        let expect = oracle(&m, start, end, &input);
        for c in [0, chunk, 1] {
            let (p, _) = split_chunked(&m, &input, c);
            let got: Vec<(Vec<u8>, bool)> = p.into_iter().map(|p| (p.data, p.complete)).collect();
            prop_assert_eq!(&got, &expect, "chunk {}", c);
        }
    }
}
