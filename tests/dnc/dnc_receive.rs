//! Receiving into real files: names and workpiece directories, atomic filing, cut-off and
//! broken transfers, existing files, unsafe names, the `receive` command on files, standard
//! input and a real TCP port.

use std::collections::BTreeMap;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ncchannel::dnc::{
    self, Anchor, Disposition, Markers, ProgramWriter, Splitter, TransferEnd, TransferLimits,
    WriterConfig,
};

const ARCHIVE: &str = "\
junk before the first start\r
%_N_SHAFT_MPF\r
;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r
N10 G0 X0 Z0\r
N20 L CONTOUR\r
N30 M30\r
%_N_CONTOUR_SPF\r
;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r
N10 G1 X10\r
N20 M17\r
%_N_MAIN_MPF\r
;$PATH=/_N_MPF_DIR\r
N10 G0 X1\r
N20 M30\r
";

/// A reader handing out at most `n` bytes per read, like a slow serial line.
struct Trickle<'a> {
    data: &'a [u8],
    n: usize,
    /// Fail with this error once the data is used up (a broken connection).
    fail_at_end: bool,
}

impl Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.data.is_empty() && self.fail_at_end {
            return Err(io::Error::new(
                io::ErrorKind::ConnectionReset,
                "line dropped",
            ));
        }
        let k = self.n.min(buf.len()).min(self.data.len());
        buf[..k].copy_from_slice(&self.data[..k]);
        self.data = &self.data[k..];
        Ok(k)
    }
}

fn markers(start: &[&str], end: &[&str]) -> Markers {
    Markers::new(start, end, Anchor::Anywhere).unwrap()
}

/// Every file under `dir`, relative path → contents.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(base: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(rd) = std::fs::read_dir(dir) else {
            return;
        };
        for e in rd {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                let rel = p
                    .strip_prefix(base)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn receive_into(
    dir: &Path,
    m: &Markers,
    data: &[u8],
    chunk: usize,
    cfg: impl FnOnce(&mut WriterConfig),
) -> dnc::TransferReport {
    let mut c = WriterConfig::new(dir);
    cfg(&mut c);
    let mut w = ProgramWriter::new(c);
    let mut s = Splitter::new(m.clone());
    let input = Trickle {
        data,
        n: chunk,
        fail_at_end: false,
    };
    dnc::receive(input, &mut s, &mut w).unwrap()
}

#[test]
fn archive_lands_in_workpiece_directories() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    let r = receive_into(
        &out,
        &markers(&["%"], &["M30", "M17"]),
        ARCHIVE.as_bytes(),
        4096,
        |_| {},
    );
    assert_eq!(r.end, TransferEnd::Complete);
    assert_eq!(r.filed(), 3);
    let t = tree(&out);
    assert_eq!(
        t.keys().collect::<Vec<_>>(),
        ["MAIN.mpf", "SHAFT.wpd/CONTOUR.spf", "SHAFT.wpd/SHAFT.mpf"]
    );
    assert_eq!(
        t["SHAFT.wpd/SHAFT.mpf"],
        b"%_N_SHAFT_MPF\r\n;$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r\nN10 G0 X0 Z0\r\nN20 L CONTOUR\r\nN30 M30\r\n"
    );
    assert!(r
        .programs
        .iter()
        .all(|p| p.disposition == Disposition::Written));
    assert_eq!(r.programs[0].path, out.join("SHAFT.wpd").join("SHAFT.mpf"));
}

#[test]
fn a_name_taken_by_a_file_or_folder_drops_only_that_program() {
    // `%X.wpd` files a program named `X.wpd`; a later program in workpiece `X` would need a
    // folder of that name. That program is not filed; the others of the transfer are.
    let data = "%X.wpd\r\nN1 G1 X1\r\nM30\r\n\
                %_N_PART_MPF\r\n;$PATH=/_N_WKS_DIR/_N_X_WPD\r\nN1 G1 X2\r\nM30\r\n\
                %_N_NEXT_MPF\r\nN1 G1 X3\r\nM30\r\n";
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    std::fs::create_dir_all(out.join("NEXT.mpf")).unwrap();
    let r = receive_into(&out, &markers(&["%"], &["M30"]), data.as_bytes(), 7, |_| {});
    assert_eq!(r.end, TransferEnd::Complete);
    let d: Vec<Disposition> = r.programs.iter().map(|p| p.disposition).collect();
    assert_eq!(
        d,
        [
            Disposition::Written,
            Disposition::NameUnusable,
            Disposition::NameUnusable
        ]
    );
    assert!(r.programs[1]
        .reason
        .as_deref()
        .unwrap()
        .contains("not a folder"));
    assert!(r.programs[2]
        .reason
        .as_deref()
        .unwrap()
        .contains("is a folder"));
    let t = tree(&out);
    assert_eq!(t.keys().collect::<Vec<_>>(), ["X.wpd"]);
    assert!(temp_files(&out).is_empty(), "no temporary file left behind");
}

#[test]
fn every_chunk_size_from_1_to_64_gives_identical_files() {
    let mut data = ARCHIVE.as_bytes().to_vec();
    data.extend_from_slice(b"%\nN1 G0\nN2 M30\n%\nN1 G1\nN2 M30\n");
    for (start, end) in [
        (&["%"][..], &["M30", "M17"][..]),
        (&["%"][..], &[][..]),
        (&[][..], &["M30"][..]),
    ] {
        let m = markers(start, end);
        let reference = tempfile::tempdir().unwrap();
        receive_into(reference.path(), &m, &data, 1 << 16, |_| {});
        let want = tree(reference.path());
        assert!(want.len() >= 4, "{start:?} {end:?}: {:?}", want.keys());
        for chunk in 1..=64 {
            let d = tempfile::tempdir().unwrap();
            receive_into(d.path(), &m, &data, chunk, |_| {});
            assert_eq!(tree(d.path()), want, "{start:?} {end:?} chunk {chunk}");
        }
    }
}

#[test]
fn unnamed_programs_are_numbered_past_existing_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("received_001.nc"), "old").unwrap();
    let r = receive_into(
        dir.path(),
        &markers(&[], &["M30"]),
        b"N1\nM30\nN2\nM30\n",
        7,
        |_| {},
    );
    let t = tree(dir.path());
    assert_eq!(t["received_001.nc"], b"old");
    assert_eq!(t["received_002.nc"], b"N1\nM30\n");
    assert_eq!(t["received_003.nc"], b"N2\nM30\n");
    assert_eq!(r.filed(), 2);
}

#[test]
fn an_existing_program_is_kept_unless_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("P1.nc"), "old").unwrap();
    let m = markers(&["%"], &["M30"]);
    let r = receive_into(dir.path(), &m, b"%P1\nM30\n", 3, |_| {});
    assert_eq!(r.programs[0].disposition, Disposition::KeptExisting);
    assert_eq!(r.filed(), 0);
    assert_eq!(tree(dir.path()).len(), 1, "no temporary file left");
    assert_eq!(std::fs::read(dir.path().join("P1.nc")).unwrap(), b"old");
    let r = receive_into(dir.path(), &m, b"%P1\nM30\n", 3, |c| c.overwrite = true);
    assert_eq!(r.programs[0].disposition, Disposition::Replaced);
    assert_eq!(
        std::fs::read(dir.path().join("P1.nc")).unwrap(),
        b"%P1\nM30\n"
    );
}

#[test]
fn a_cut_off_transfer_leaves_no_file_under_the_final_name() {
    let m = markers(&["%"], &["M30"]);
    let data = b"%_N_DONE_MPF\nN1\nM30\n%_N_HALF_MPF\n;$PATH=/_N_WKS_DIR/_N_W_WPD\nN1 G1 X";
    let dir = tempfile::tempdir().unwrap();
    let r = receive_into(dir.path(), &m, data, 5, |_| {});
    assert_eq!(r.split.cut_off, 1);
    assert_eq!(r.programs[1].disposition, Disposition::CutOffDropped);
    let t = tree(dir.path());
    assert_eq!(
        t.keys().collect::<Vec<_>>(),
        ["DONE.mpf"],
        "no partial, no temp file"
    );

    // With keep_partial the piece is kept, but never under the final name.
    let dir = tempfile::tempdir().unwrap();
    let r = receive_into(dir.path(), &m, data, 5, |c| c.keep_partial = true);
    assert_eq!(r.programs[1].disposition, Disposition::CutOffKept);
    let t = tree(dir.path());
    assert_eq!(
        t.keys().collect::<Vec<_>>(),
        ["DONE.mpf", "W.wpd/HALF.mpf.partial"]
    );
    assert!(!dir.path().join("W.wpd/HALF.mpf").exists());
}

#[test]
fn a_broken_connection_never_files_the_open_program() {
    // End-only mode files the last block at a normal end of data, but not when the line broke.
    let m = markers(&[], &["M30"]);
    let dir = tempfile::tempdir().unwrap();
    let mut w = ProgramWriter::new(WriterConfig::new(dir.path()));
    let mut s = Splitter::new(m);
    let input = Trickle {
        data: b"%_N_A_MPF\nM30\n%_N_B_MPF\nN1 G0\n",
        n: 4,
        fail_at_end: true,
    };
    let r = dnc::receive(input, &mut s, &mut w).unwrap();
    assert!(matches!(r.end, TransferEnd::Broken(_)));
    assert_eq!(tree(dir.path()).keys().collect::<Vec<_>>(), ["A.mpf"]);
    assert_eq!(r.programs[1].disposition, Disposition::CutOffDropped);
}

#[test]
fn names_from_the_data_never_leave_the_program_directory() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    let data = "%_N_.._.._EVIL_MPF\nM30\n%_N_X_MPF\n;$PATH=/_N_WKS_DIR/_N_.._WPD\nM30\n%../evil\nM30\n%/tmp/abs\nM30\n";
    let r = receive_into(
        &out,
        &markers(&["%"], &["M30"]),
        data.as_bytes(),
        64,
        |_| {},
    );
    assert_eq!(r.filed(), 4);
    assert_eq!(
        tree(root.path()).keys().collect::<Vec<_>>(),
        [
            "out/X.mpf",
            "out/received_001.nc",
            "out/received_002.nc",
            "out/received_003.nc"
        ]
    );
    assert!(r.programs.iter().all(|p| p.path.starts_with(&out)));
    assert_eq!(r.programs[0].rejected_names.len(), 1);
    assert_eq!(r.programs[1].rejected_names.len(), 1, "the workpiece");
}

// ---- the command line -------------------------------------------------------------------

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
}

#[test]
fn cli_files_an_archive_from_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.txt");
    std::fs::write(&input, ARCHIVE).unwrap();
    let out = dir.path().join("prog");
    let o = bin()
        .arg("receive")
        .arg(&input)
        .args(["--start", "%", "--end", "M30", "--end", "M17", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    assert_eq!(
        stdout
            .lines()
            .filter(|l| l.starts_with("received "))
            .count(),
        3
    );
    assert!(stdout.contains("3 program(s) filed"), "{stdout}");
    assert_eq!(tree(&out).len(), 3);
}

/// A refused name is reported with what was done instead: a refused workpiece folder files the
/// program at the top under its own name (not numbered), a refused program name numbers it.
#[test]
fn cli_says_where_a_program_with_a_refused_name_went() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.txt");
    std::fs::write(
        &input,
        "%_N_PART_MPF\n;$PATH=/_N_WKS_DIR/_N_.._WPD\nN10 G0 X1\nM30\n%_N_../EVIL_MPF\nM30\n",
    )
    .unwrap();
    let out = dir.path().join("prog");
    let o = bin()
        .arg("receive")
        .arg(&input)
        .args(["--start", "%", "--end", "M30", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert_eq!(
        tree(&out).keys().collect::<Vec<_>>(),
        ["PART.mpf", "received_001.nc"]
    );
    let part = out.join("PART.mpf");
    assert!(
        stderr.contains(&format!(
            "workpiece folder name `..` in lines 1-4 is not a plain name; filed as {} instead",
            part.display()
        )),
        "{stderr}"
    );
    let numbered = out.join("received_001.nc");
    assert!(
        stderr.contains(&format!(
            "program name `../EVIL_MPF` in lines 5-6 is not a plain name; filed as {} instead",
            numbered.display()
        )),
        "{stderr}"
    );
    assert!(!stderr.contains("numbered instead"), "{stderr}");
}

#[test]
fn cli_start_only_without_a_start_discards_all_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    let mut child = bin()
        .args(["receive", "-", "--start", "%", "--out"])
        .arg(&out)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"N10 G0 X1\nN20 M30\n")
        .unwrap();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("no start marker found"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(tree(&out).is_empty());
}

#[test]
fn cli_bad_usage_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.txt");
    std::fs::write(&input, "x\n").unwrap();
    for args in [
        &[
            "--start", "a", "--start", "b", "--start", "c", "--start", "d",
        ][..],
        &["--end", "1", "--end", "2", "--end", "3", "--end", "4"][..],
        &["--end", ""][..],
        &["--name-template", "../x{n}.nc"][..],
        &["--max-transfers", "2"][..],
    ] {
        let o = bin()
            .arg("receive")
            .arg(&input)
            .args(args)
            .arg("--out")
            .arg(dir.path().join("o"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
    }
}

/// Start `receive --listen` on an ephemeral loopback port; returns the child and the port.
fn listen(
    out: &Path,
    extra: &[&str],
) -> (
    std::process::Child,
    u16,
    BufReader<std::process::ChildStderr>,
) {
    let mut child = bin()
        .args(["receive", "--listen", "127.0.0.1:0", "--out"])
        .arg(out)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    let port = line
        .trim()
        .rsplit(':')
        .next()
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));
    (child, port, err)
}

#[test]
fn cli_listen_takes_transfers_one_after_another() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    let (child, port, mut err) = listen(
        &out,
        &["--start", "%", "--end", "M30", "--max-transfers", "2"],
    );
    for t in [&b"%A\nN1\nM30\n%B\nM30\n"[..], &b"noise\n%C\r\nM30\r\n"[..]] {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        s.write_all(t).unwrap();
        // Closing the connection ends the transfer.
    }
    let o = child.wait_with_output().unwrap();
    let mut rest = String::new();
    err.read_to_string(&mut rest).unwrap();
    assert_eq!(o.status.code(), Some(0), "{rest}");
    let t = tree(&out);
    assert_eq!(t.keys().collect::<Vec<_>>(), ["A.nc", "B.nc", "C.nc"]);
    assert_eq!(t["C.nc"], b"%C\r\nM30\r\n");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("3 program(s) filed"), "{stdout}");
    assert!(stdout.contains("2 transfer(s)"), "{stdout}");
}

/// Wait for a condition; the deadline is generous, since it only matters when the behaviour
/// is broken, and a loaded machine must not turn a pass into a failure.
fn wait_for(what: &str, mut f: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn temp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "tmp"))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn a_program_appears_under_its_name_only_when_complete_even_if_the_receiver_dies() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    let (mut child, port, _err) = listen(&out, &["--start", "%", "--end", "M30"]);
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.write_all(b"%_N_DONE_MPF\nM30\n%_N_BIG_MPF\nN1 G1 X1\n")
        .unwrap();
    s.flush().unwrap();
    wait_for("DONE.mpf", || out.join("DONE.mpf").exists());
    wait_for("the temporary file of BIG", || !temp_files(&out).is_empty());
    assert!(!out.join("BIG.mpf").exists());
    // The receiver crashes in the middle of the program.
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("BIG.mpf").exists());
    assert_eq!(
        std::fs::read(out.join("DONE.mpf")).unwrap(),
        b"%_N_DONE_MPF\nM30\n"
    );
}

#[test]
fn library_listener_files_after_the_end_line_and_drops_a_cut_off_connection() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_path_buf();
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let out2 = out.clone();
    let server = std::thread::spawn(move || {
        let listen = dnc::Listener {
            max_transfers: Some(2),
            ..dnc::Listener::new(
                markers(&["%"], &["M30"]),
                WriterConfig::new(&out2),
                TransferLimits::default(),
            )
        };
        let mut reports = Vec::new();
        let n = listen.serve(
            &listener,
            &dnc::StopRequest::new(),
            |_| {},
            |r| reports.push(r.unwrap()),
            |e| panic!("{e}"),
        );
        (n, reports)
    });
    let mut c = TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.write_all(b"%P1\nN1 G0\n").unwrap();
    wait_for("the temporary file", || !temp_files(&out).is_empty());
    assert!(!out.join("P1.nc").exists());
    c.write_all(b"N2 M30\n").unwrap();
    wait_for("P1.nc", || out.join("P1.nc").exists());
    drop(c);
    // The second sender hangs up inside a program.
    let mut c = TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.write_all(b"%P2\nN1 G0\n").unwrap();
    drop(c);
    let (n, reports) = server.join().unwrap();
    assert_eq!(n, 2);
    assert_eq!(reports[0].filed(), 1);
    assert_eq!(reports[1].split.cut_off, 1);
    assert!(reports[1].peer.is_some());
    assert_eq!(tree(&out).keys().collect::<Vec<_>>(), ["P1.nc"]);
}

#[test]
fn a_silent_connection_times_out_as_a_broken_transfer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_path_buf();
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    // One whole program, then the sender stalls inside the next one. Sent before the
    // listener accepts, so the 200 ms idle timeout cannot run out before the data is there.
    let mut c = TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.write_all(b"%_N_A_MPF\nM30\n%_N_B_MPF\nN1\n").unwrap();
    let out2 = out.clone();
    let server = std::thread::spawn(move || {
        let listen = dnc::Listener {
            max_transfers: Some(1),
            ..dnc::Listener::new(
                markers(&[], &["M30"]),
                WriterConfig::new(&out2),
                TransferLimits {
                    idle_timeout: Some(Duration::from_millis(200)),
                    ..TransferLimits::default()
                },
            )
        };
        let mut reports = Vec::new();
        listen.serve(
            &listener,
            &dnc::StopRequest::new(),
            |_| {},
            |r| reports.push(r.unwrap()),
            |e| panic!("{e}"),
        );
        reports
    });
    let reports = server.join().unwrap();
    drop(c);
    assert_eq!(reports[0].end, TransferEnd::IdleTimeout);
    assert_eq!(reports[0].filed(), 1);
    assert_eq!(
        reports[0].programs[1].disposition,
        Disposition::CutOffDropped
    );
    assert_eq!(tree(&out).keys().collect::<Vec<_>>(), ["A.mpf"]);
}

#[test]
fn without_out_programs_land_in_the_channels_first_program_path() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("params")).unwrap();
    std::fs::create_dir_all(d.path().join("progs")).unwrap();
    std::fs::write(
        d.path().join("params/startup.lis"),
        "kanal_anzahl 1\nsda_mds[0] ch.lis\npfad[0].prg[0] ../progs\npfad[0].typ[0] 0x01\n",
    )
    .unwrap();
    std::fs::write(d.path().join("params/ch.lis"), "streaming_prog_file s.nc\n").unwrap();
    let input = d.path().join("in.txt");
    std::fs::write(&input, "%_N_PART1_MPF\nG1 X1 F100\nM30\n").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args([
            "receive",
            input.to_str().unwrap(),
            "--end",
            "M30",
            "--params",
        ])
        .arg(d.path().join("params/startup.lis"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.path().join("progs/PART1.mpf").is_file());
}

#[test]
fn receive_help_keeps_the_name_template_on_one_line() {
    // clap turns a literal `{n}` in help text into a line break: the template's own syntax
    // must not break the text that explains it.
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["receive", "--help"])
        .output()
        .expect("ncchannel runs");
    let help = String::from_utf8_lossy(&out.stdout);
    let line = help
        .lines()
        .find(|l| l.contains("--name-template"))
        .unwrap_or_default();
    assert!(
        line.contains("`{n:W}`") && line.contains("[default: received_{n}.nc]"),
        "{help}"
    );
}
