//! The command line's outputs as a user meets them: `run --plot` draws the tool path at 1:1
//! (a circle is round, measured in the SVG file) with side views that show a bend out of the
//! plane, PNG for `.png`; an unknown picture extension or a file that cannot be written is
//! exit 2; `-` means standard output for every output option; `check` takes the shipped
//! params/ folder and soak scenarios; completions and the man page come from the binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ncchannel(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Write an NC program into `dir`; its path as an argument.
fn program(dir: &Path, name: &str, body: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p.to_str().unwrap().to_string()
}

/// The polylines of the tool path (its colour, more than the two points of a legend sample),
/// in document order: the plane view, then the two side views. Points in px.
fn path_polylines(svg: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| {
            p.split('>')
                .next()
                .is_some_and(|t| t.contains("stroke=\"#1F5FBF\""))
        })
        .filter_map(|p| {
            let pts = p.split("points=\"").nth(1)?.split('"').next()?;
            let v: Vec<(f64, f64)> = pts
                .split_whitespace()
                .filter_map(|xy| {
                    let (x, y) = xy.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            (v.len() > 2).then_some(v)
        })
        .collect()
}

/// Width and height of the points' bounding box, px.
fn extent(points: &[(f64, f64)]) -> (f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    (x1 - x0, y1 - y0)
}

#[test]
fn plot_draws_a_circle_round_and_a_bend_out_of_the_plane_in_its_side_view() {
    let dir = tempfile::tempdir().unwrap();
    // A full R35 circle about the origin (G17), reached along X from the centre.
    let circle = program(
        dir.path(),
        "circle.nc",
        "G90 G17 G1 X35 Y0 F6000\nG2 X35 Y0 I-35 J0\nM30\n",
    );
    let svg_path = dir.path().join("circle.svg");
    let out = ncchannel(&["run", &circle, "--plot", svg_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let views = path_polylines(&svg);
    assert_eq!(views.len(), 3, "plane view and two side views");
    let (w, h) = extent(&views[0]);
    assert!(w > 200.0, "the circle fills its view: {w} px");
    assert!(
        (w / h - 1.0).abs() < 0.01,
        "a circle is round: {w} × {h} px"
    );
    for label in [
        "G17 plane X–Y, 1:1",
        "side view X–Z",
        "side view Y–Z",
        "X (mm)",
        "Z (mm)",
    ] {
        assert!(svg.contains(label), "{label}");
    }

    // Up 10 mm and down again over 20 mm of Y: a straight line in the X–Y plane, a
    // triangle twice as wide as high in the Y–Z side view.
    let bend = program(
        dir.path(),
        "bend.nc",
        "G90 G17 G1 Y10 Z10 F3000\nY20 Z0\nM30\n",
    );
    let svg_path = dir.path().join("bend.svg");
    let out = ncchannel(&["run", &bend, "--plot", svg_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let views = path_polylines(&std::fs::read_to_string(&svg_path).unwrap());
    let (w, h) = extent(&views[2]);
    assert!(
        (w / h - 2.0).abs() < 0.03,
        "Y–Z side view at 1:1 shows the bend: {w} × {h} px"
    );
    let (w, _) = extent(&views[0]);
    assert!(
        w < 2.0,
        "in the plane the path is a line along Y: {w} px wide"
    );
}

#[test]
fn plot_writes_png_for_png_and_refuses_an_unknown_extension() {
    let dir = tempfile::tempdir().unwrap();
    let png_path = dir.path().join("square.png");
    let out = ncchannel(&[
        "run",
        "contour_square.nc",
        "--plot",
        png_path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let bytes = std::fs::read(&png_path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    assert_eq!((reader.info().width, reader.info().height), (1500, 1000));
    let mut pixels = vec![0; reader.output_buffer_size()];
    reader.next_frame(&mut pixels).unwrap();
    let drawn = pixels.chunks(3).filter(|p| p != &[255, 255, 255]).count();
    assert!(
        drawn > 10_000,
        "the picture is drawn: {drawn} non-white pixels"
    );

    let jpg = dir.path().join("square.jpg");
    let out = ncchannel(&["run", "contour_square.nc", "--plot", jpg.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains(".svg or .png"),
        "{}",
        text(&out.stderr)
    );
    assert!(!jpg.exists(), "nothing written");
}

#[test]
fn an_output_that_cannot_be_written_is_exit_2() {
    for opt in ["--plot", "--report"] {
        let out = ncchannel(&["run", "contour_square.nc", opt, "/no/such/dir/x.svg"]);
        assert_eq!(out.status.code(), Some(2), "{opt}: {}", text(&out.stderr));
        assert!(text(&out.stderr).contains(opt), "{}", text(&out.stderr));
    }
}

#[test]
fn dash_is_standard_output_for_report_plot_and_trace() {
    let out = ncchannel(&["run", "contour_square.nc", "--report", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["outcome"], "ended");
    assert!(text(&out.stderr).contains("ended"), "the summary on stderr");
    assert!(!Path::new(env!("CARGO_MANIFEST_DIR")).join("-").exists());

    let out = ncchannel(&["run", "contour_square.nc", "--plot", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("<svg"));
    assert!(text(&out.stdout).trim_end().ends_with("</svg>"));

    let out = ncchannel(&["run", "contour_square.nc", "--trace", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("time_s,X_mm"));

    let out = ncchannel(&["run", "contour_square.nc", "--report", "-", "--events", "-"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("at most one"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn check_takes_the_shipped_params_folder_and_knows_scenarios() {
    let out = ncchannel(&["check", "params/"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let dir = tempfile::tempdir().unwrap();
    let soak = Path::new(env!("CARGO_MANIFEST_DIR")).join("params/soak/startup.lis");
    let write = |name: &str, body: String| -> PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let typo = write(
        "typo.toml",
        format!("params = {:?}\nseeed = 1\n[length]\nblocks = 1\n", soak),
    );
    let missing = write(
        "missing.toml",
        "params = \"nosuch.lis\"\n[length]\nblocks = 1\n".into(),
    );
    let out = ncchannel(&["check", typo.to_str().unwrap(), missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let found = text(&out.stdout);
    assert!(
        found.contains("typo.toml") && found.contains("seeed"),
        "{found}"
    );
    assert!(
        found.contains("missing.toml") && found.contains("nosuch.lis"),
        "{found}"
    );
}

#[test]
fn completions_and_man_page_come_from_the_binary() {
    let out = ncchannel(&["completions", "bash"]);
    assert_eq!(out.status.code(), Some(0));
    let bash = text(&out.stdout);
    assert!(
        bash.contains("complete ") && bash.contains("--plot"),
        "{bash}"
    );
    let out = ncchannel(&["man"]);
    assert_eq!(out.status.code(), Some(0));
    let man = text(&out.stdout);
    assert!(
        man.contains(".TH ncchannel 1") && man.contains("soak"),
        "{man}"
    );
    assert_eq!(
        ncchannel(&["completions", "nosuchshell"]).status.code(),
        Some(2)
    );
    // A subcommand's page carries its options.
    let out = ncchannel(&["man", "run"]);
    assert_eq!(out.status.code(), Some(0));
    let run = text(&out.stdout);
    assert!(
        run.contains(".TH ncchannel-run 1") && run.contains("\\-\\-plot"),
        "{run}"
    );
    assert_eq!(ncchannel(&["man", "nosuchcommand"]).status.code(), Some(2));
    // --dir writes every page the main page names, each with its options.
    let dir = tempfile::tempdir().expect("temp dir");
    let out = ncchannel(&["man", "--dir", &dir.path().display().to_string()]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let named: Vec<String> = man
        .lines()
        .filter_map(|l| l.strip_prefix("ncchannel\\-"))
        .filter_map(|l| l.strip_suffix("(1)"))
        .map(|sub| format!("ncchannel-{}.1", sub.replace("\\-", "-")))
        .collect();
    assert!(named.len() >= 10, "{named:?}");
    for page in &named {
        let body = std::fs::read_to_string(dir.path().join(page))
            .unwrap_or_else(|e| panic!("{page} named by the main page: {e}"));
        assert!(body.contains(".SH OPTIONS"), "{page}: {body}");
    }
}
