//! Parameter lists end to end: real files in temporary folders through `params::load` and
//! `params::check_list_file`.

use std::fs;
use std::path::{Path, PathBuf};

use ncchannel::params::{self, ParamError, RuntimeConfig, MAIN_PROGRAMS, SUBROUTINES};
use ncchannel::{Diagnostic, Severity};
use proptest::prelude::*;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    if let Some(parent) = p.parent() {
        fs::create_dir_all(parent).unwrap();
    }
    fs::write(&p, text).unwrap();
    p
}

fn errors_of(r: Result<params::Config, ParamError>) -> Vec<Diagnostic> {
    match r {
        Ok(c) => panic!("expected an error, loaded {} channel(s)", c.channels.len()),
        Err(e) => e.errors(),
    }
}

/// The single error, asserting its place and that the message names the parameter.
fn one_error(errs: &[Diagnostic], file: &Path, line: usize, col: usize, param: &str) {
    assert_eq!(errs.len(), 1, "{errs:#?}");
    let d = &errs[0];
    assert_eq!(d.severity, Severity::Error);
    assert_eq!(d.file, file, "{d}");
    assert_eq!((d.line, d.col), (line, col), "{d}");
    assert!(
        d.message.contains(param),
        "message does not name {param}: {d}"
    );
}

const CHANNEL: &str = "streaming_prog_file streaming.nc\n";

#[test]
fn shipped_files_load_without_error_or_warning() {
    let startup = Path::new(env!("CARGO_MANIFEST_DIR")).join("params/startup.lis");
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert!(cfg.warnings.is_empty(), "{:#?}", cfg.warnings);
    assert_eq!(cfg.channels.len(), 1);
    let ch = &cfg.channels[0];
    assert_eq!(ch.streaming_prog_file.as_deref(), Some("streaming.nc"));
    assert!(ch.decoder.cache.enabled);
    assert_eq!(
        (ch.decoder.cache.max_files, ch.decoder.cache.max_file_bytes),
        (6, 6000)
    );
    let base = startup.parent().unwrap();
    assert_eq!(ch.list_path, base.join("channel1.lis"));
    assert_eq!(ch.search_paths.len(), 1);
    assert_eq!(ch.search_paths[0].dir, base.join("../nc"));
    assert_eq!(ch.search_paths[0].kinds, MAIN_PROGRAMS | SUBROUTINES);
    assert_eq!(
        cfg.runtime_file.as_deref(),
        Some(base.join("runtime.toml").as_path())
    );
    // The shipped runtime.toml writes down the built-in defaults, but for the two decoder
    // keys that let a client stream 17-byte lines at the interface's full rate: a tick
    // decodes and passes on a whole 4094-byte buffer of them (241 blocks).
    let mut expected = RuntimeConfig::default();
    expected.decoder.blocks_per_tick = 256;
    expected.decoder.buffer_blocks = 224;
    assert_eq!(cfg.runtime, expected);
    let queue = expected.planner.lookahead_blocks + expected.decoder.buffer_blocks;
    // More than a full buffer of 17-byte lines (240.8) a tick.
    assert!(expected.decoder.blocks_per_tick.min(queue) as usize > 4094 / 17);
    assert!(params::check_list_file(&startup).is_empty());
    assert!(params::check_list_file(&base.join("channel1.lis")).is_empty());
    assert!(params::check_list_file(&base.join("runtime.toml")).is_empty());
}

#[test]
fn good_lists_with_two_channels_and_relative_paths() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let startup = write(
        d,
        "cnc/startup.lis",
        "# two channels\n\
         kanal_anzahl 2\n\
         sda_mds[0] ch1.lis\n\
         sda_mds[1] lists/ch2.lis\n\
         pfad[0].prg[0] progs\n\
         pfad[0].typ[0] 0x01\n\
         pfad[0].prioritaet[0] 1\n\
         pfad[0].prg[1] subs\n\
         pfad[0].typ[1] 0x02\n\
         pfad[0].prioritaet[1] 0\n\
         pfad[0].prg[2] /abs/both\n\
         pfad[0].typ[2] 3\n\
         pfad[0].prioritaet[2] 2\n\
         pfad[1].prg[0] progs\n\
         pfad[1].typ[0] 0x03\n",
    );
    write(d, "cnc/ch1.lis", CHANNEL);
    write(
        d,
        "cnc/lists/ch2.lis",
        "streaming_prog_file \"\"\npath[0].dir ../own\npath[0].type 0x03\n",
    );
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert!(cfg.warnings.is_empty(), "{:#?}", cfg.warnings);
    assert_eq!(cfg.runtime_file, None);
    assert_eq!(cfg.runtime, RuntimeConfig::default());

    let cnc = d.join("cnc");
    let c0 = &cfg.channels[0];
    assert_eq!(c0.list_path, cnc.join("ch1.lis"));
    // Sorted by priority; relative to the start-up list's folder; absolute kept.
    let dirs: Vec<_> = c0.search_paths.iter().map(|p| p.dir.clone()).collect();
    assert_eq!(
        dirs,
        vec![
            cnc.join("subs"),
            cnc.join("progs"),
            PathBuf::from("/abs/both")
        ]
    );
    let main: Vec<_> = c0.main_program_paths().collect();
    assert_eq!(
        main,
        vec![cnc.join("progs").as_path(), Path::new("/abs/both")]
    );
    let subs: Vec<_> = c0.subroutine_paths().collect();
    assert_eq!(
        subs,
        vec![cnc.join("subs").as_path(), Path::new("/abs/both")]
    );
    assert!(!c0.paths_from_channel_list);
    assert!(!c0.decoder.cache.enabled);
    assert_eq!(c0.decoder.cache.max_files, 0);

    let c1 = &cfg.channels[1];
    assert_eq!(c1.index, 1);
    assert_eq!(c1.list_path, cnc.join("lists/ch2.lis"));
    assert_eq!(c1.streaming_prog_file, None, "empty string = streaming off");
    // The channel list's paths replace pfad[1].*, relative to the CNC's working directory
    // (the start-up list's folder here), not to the channel list's own folder.
    assert!(c1.paths_from_channel_list);
    assert_eq!(c1.search_paths.len(), 1);
    assert_eq!(c1.search_paths[0].dir, cnc.join("../own"));
}

#[test]
fn channel_list_overrides_cache_values() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] ch.lis\n\
         configuration.channel[0].decoder.function FCT_USE_CACHED_FILES\n\
         configuration.channel[0].decoder.max_cache_number 6\n\
         configuration.channel[0].decoder.max_cache_size 6000\n",
    );
    write(
        t.path(),
        "ch.lis",
        "configuration.decoder.max_cache_size 0x2000\n",
    );
    let cfg = params::load(&startup).unwrap();
    let cache = cfg.channels[0].decoder.cache;
    assert!(cache.enabled);
    assert_eq!((cache.max_files, cache.max_file_bytes), (6, 0x2000));

    // The channel list can switch caching off; the explicit start-up sizes stay but warn.
    write(t.path(), "ch.lis", "configuration.decoder.function -\n");
    let cfg = params::load(&startup).unwrap();
    assert!(!cfg.channels[0].decoder.cache.enabled);
    assert_eq!(cfg.warnings.len(), 2, "{:#?}", cfg.warnings);

    // And on: defaults 4 × 4096 when no sizes are given anywhere.
    write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] ch.lis\n",
    );
    write(
        t.path(),
        "ch.lis",
        "configuration.decoder.function FCT_USE_CACHED_FILES\n",
    );
    let cfg = params::load(&startup).unwrap();
    let cache = cfg.channels[0].decoder.cache;
    assert!(cache.enabled);
    assert_eq!((cache.max_files, cache.max_file_bytes), (4, 4096));
}

#[test]
fn unknown_entry_is_a_warning_and_kept() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] ch.lis\n# axes are not emulated here\nachs_anzahl 3\n",
    );
    let ch = write(
        t.path(),
        "ch.lis",
        "streaming_prog_file s.nc\n\nmystery.value \"a b\"\n",
    );
    let cfg = params::load(&startup).unwrap();
    assert_eq!(cfg.warnings.len(), 2, "{:#?}", cfg.warnings);
    let w = &cfg.warnings[0];
    assert_eq!(w.severity, Severity::Warning);
    assert_eq!((w.file.as_path(), w.line, w.col), (startup.as_path(), 4, 1));
    assert!(w.message.contains("achs_anzahl"));
    assert!(w
        .to_string()
        .starts_with(&format!("{}:4:1: warning", startup.display())));
    let w = &cfg.warnings[1];
    assert_eq!((w.file.as_path(), w.line), (ch.as_path(), 3));
    // Kept, and reachable by name.
    assert_eq!(
        cfg.startup.get("achs_anzahl").unwrap().value.as_int(),
        Some(3)
    );
    assert_eq!(
        cfg.channels[0]
            .list
            .get("mystery.value")
            .unwrap()
            .value
            .as_str(),
        "a b"
    );
}

#[test]
fn malformed_line_is_an_error_at_its_line_and_column() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\r\nsda_mds[0] ch.lis\r\n\r\n\tpfad[0].prg[0]\r\n",
    );
    write(t.path(), "ch.lis", CHANNEL);
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &startup, 4, 16, "pfad[0].prg[0]");
    assert!(
        errs[0].render().contains("\tpfad[0].prg[0]\n"),
        "{}",
        errs[0].render()
    );

    // In the channel list, a string without its closing quote.
    write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] ch.lis\n",
    );
    let ch = write(t.path(), "ch.lis", "streaming_prog_file \"my stream.nc\n");
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &ch, 1, 21, "closing");
}

#[test]
fn hex_quoted_strings_and_comments() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 0x1 (one channel)\n\
         sda_mds[0] \"chan (1).lis\" (quoted because of the parenthesis)\n\
         pfad[0].prg[0] \"my programs\"   (folder with a blank)\n\
         pfad[0].typ[0] 0x03 main and subroutines\n\
         pfad[0].prioritaet[0] 0\tfirst\n\
         configuration.channel[0].decoder.max_cache_size 0x1000 bytes\n\
         configuration.channel[0].decoder.function FCT_USE_CACHED_FILES (cache on)\n",
    );
    write(
        t.path(),
        "chan (1).lis",
        "streaming_prog_file \"stream (x).nc\" (comment)\n",
    );
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert!(cfg.warnings.is_empty(), "{:#?}", cfg.warnings);
    let c = &cfg.channels[0];
    assert_eq!(c.streaming_prog_file.as_deref(), Some("stream (x).nc"));
    assert_eq!(c.search_paths[0].dir, t.path().join("my programs"));
    assert_eq!(c.search_paths[0].kinds, 3);
    assert_eq!(c.decoder.cache.max_file_bytes, 4096);
    assert_eq!(c.decoder.cache.max_files, 4);
}

/// One implausible value: load fails with a single error at (line, col) naming `param`,
/// and `check` reports the same error.
fn implausible(startup_text: &str, channel_text: &str, at: (bool, usize, usize), param: &str) {
    let (in_channel, line, col) = at;
    let t = tempfile::tempdir().unwrap();
    let startup = write(t.path(), "startup.lis", startup_text);
    let ch = write(t.path(), "ch.lis", channel_text);
    let errs = errors_of(params::load(&startup));
    one_error(
        &errs,
        if in_channel { &ch } else { &startup },
        line,
        col,
        param,
    );
    let checked: Vec<_> = params::check_list_file(&startup)
        .into_iter()
        .filter(|d| d.severity == Severity::Error)
        .collect();
    assert_eq!(checked, errs);
}

const STARTUP: &str = "kanal_anzahl 1\nsda_mds[0] ch.lis\n";
const IN_STARTUP: bool = false;
const IN_CHANNEL: bool = true;

#[test]
fn negative_cache_size_is_an_error() {
    implausible(
        &format!("{STARTUP}configuration.channel[0].decoder.max_cache_size -1\n"),
        CHANNEL,
        (IN_STARTUP, 3, 49),
        "configuration.channel[0].decoder.max_cache_size",
    );
    implausible(
        STARTUP,
        "configuration.decoder.max_cache_number -4\n",
        (IN_CHANNEL, 1, 40),
        "configuration.decoder.max_cache_number",
    );
}

#[test]
fn channel_index_not_below_kanal_anzahl_is_an_error() {
    implausible(
        &format!("{STARTUP}sda_mds[1] ch.lis\n"),
        CHANNEL,
        (IN_STARTUP, 3, 1),
        "sda_mds[1]",
    );
    implausible(
        &format!("{STARTUP}pfad[2].prg[0] x\n"),
        CHANNEL,
        (IN_STARTUP, 3, 1),
        "pfad[2].prg[0]",
    );
    implausible(
        &format!("{STARTUP}configuration.channel[1].decoder.max_cache_size 5\n"),
        CHANNEL,
        (IN_STARTUP, 3, 1),
        "configuration.channel[1]",
    );
    // P-STUP-00010 / -00011: the tool and zero-offset lists are per channel as well.
    for name in ["werkz_data[1]", "nullp_data[1]"] {
        implausible(
            &format!("{STARTUP}{name} x.lis\n"),
            CHANNEL,
            (IN_STARTUP, 3, 1),
            name,
        );
    }
}

#[test]
fn two_paths_of_one_type_with_one_priority_is_an_error() {
    implausible(
        &format!(
            "{STARTUP}pfad[0].prg[0] a\npfad[0].typ[0] 0x03\npfad[0].prioritaet[0] 1\n\
             pfad[0].prg[1] b\npfad[0].typ[1] 0x02\npfad[0].prioritaet[1] 1\n"
        ),
        CHANNEL,
        (IN_STARTUP, 8, 23),
        "pfad[0].prioritaet[1]",
    );
    // Same priority but different types is fine.
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        &format!(
            "{STARTUP}pfad[0].prg[0] a\npfad[0].typ[0] 1\npfad[0].prg[1] b\npfad[0].typ[1] 2\n"
        ),
    );
    write(t.path(), "ch.lis", CHANNEL);
    assert_eq!(
        params::load(&startup).unwrap().channels[0]
            .search_paths
            .len(),
        2
    );
    // In a channel list, a missing priority defaults to 0 and clashes too.
    implausible(
        STARTUP,
        "path[0].dir a\npath[0].type 1\npath[1].dir b\npath[1].type 1\n",
        (IN_CHANNEL, 3, 1),
        "path[1].dir",
    );
}

#[test]
fn missing_or_unreadable_channel_list_is_an_error() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] nowhere.lis\n",
    );
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &startup, 2, 12, "sda_mds[0]");
    assert!(errs[0].message.contains("nowhere.lis"));

    // A folder is not a readable list.
    fs::create_dir(t.path().join("dir.lis")).unwrap();
    write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 1\nsda_mds[0] dir.lis\n",
    );
    one_error(
        &errors_of(params::load(&startup)),
        &startup,
        2,
        12,
        "sda_mds[0]",
    );

    // A channel without any sda_mds entry.
    write(t.path(), "ch.lis", CHANNEL);
    write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 2\nsda_mds[0] ch.lis\n",
    );
    one_error(
        &errors_of(params::load(&startup)),
        &startup,
        1,
        14,
        "sda_mds[1]",
    );
}

#[test]
fn channel_count_zero_absurd_or_missing_is_an_error() {
    implausible(
        "kanal_anzahl 0\n",
        CHANNEL,
        (IN_STARTUP, 1, 14),
        "kanal_anzahl",
    );
    implausible(
        "kanal_anzahl 99\nsda_mds[0] ch.lis\n",
        CHANNEL,
        (IN_STARTUP, 1, 14),
        "kanal_anzahl",
    );
    implausible(
        "kanal_anzahl two\nsda_mds[0] ch.lis\n",
        CHANNEL,
        (IN_STARTUP, 1, 14),
        "kanal_anzahl",
    );
    implausible(
        "sda_mds[0] ch.lis\n",
        CHANNEL,
        (IN_STARTUP, 1, 1),
        "kanal_anzahl",
    );
}

#[test]
fn streaming_prog_file_too_long_is_an_error() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(t.path(), "startup.lis", STARTUP);
    write(
        t.path(),
        "ch.lis",
        &format!("streaming_prog_file {}\n", "a".repeat(83)),
    );
    assert!(params::load(&startup).is_ok());
    implausible(
        STARTUP,
        &format!("# too long\nstreaming_prog_file {}\n", "a".repeat(84)),
        (IN_CHANNEL, 2, 21),
        "streaming_prog_file",
    );
}

#[test]
fn every_error_is_reported_in_one_run() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        &format!("{STARTUP}broken\npfad[0].typ[0] 1\n"),
    );
    write(
        t.path(),
        "ch.lis",
        "streaming_prog_file \"open\nconfiguration.decoder.max_cache_size x\n",
    );
    let errs = errors_of(params::load(&startup));
    assert_eq!(errs.len(), 4, "{errs:#?}");
    let rendered = ParamError::Invalid(errs).to_string();
    assert!(rendered.contains("startup.lis:3:7: error"), "{rendered}");
    assert!(rendered.contains("ch.lis:1:21: error"), "{rendered}");
}

#[test]
fn runtime_toml_absent_gives_defaults_and_unknown_key_is_an_error() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(t.path(), "startup.lis", STARTUP);
    write(t.path(), "ch.lis", CHANNEL);
    let cfg = params::load(&startup).unwrap();
    assert_eq!(cfg.runtime_file, None);
    let r = &cfg.runtime;
    assert_eq!(r.cycle_period_us, 1000);
    assert_eq!(
        r.axes.iter().map(|a| a.name.as_str()).collect::<Vec<_>>(),
        ["X", "Y", "Z"]
    );
    assert_eq!(r.axes[0].max_velocity_mm_per_min, 30000.0);
    assert_eq!(r.axes[0].soft_limit_min_mm, -1000.0);
    assert_eq!(r.decoder.blocks_per_tick, 64);
    assert_eq!(r.decoder.buffer_blocks, 8);
    assert_eq!(r.decoder.max_subroutine_depth, 20);
    assert_eq!(r.planner.lookahead_blocks, 32);
    assert_eq!((r.fs_latency_us, r.fs_latency_us_per_kib), (0, 0));
    assert_eq!(r.ads.bind.0.to_string(), "127.0.0.1:48898");
    assert_eq!(r.ads.net_id.to_string(), "127.0.0.2.1.1");
    assert_eq!(r.ads.max_frame_bytes, 65536);
    assert!(r.ads.allowed_clients.is_empty());

    let rt = write(
        t.path(),
        "runtime.toml",
        "cycle_period_us = 500\n\n[planner]\nlookahead = 4\n",
    );
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &rt, 4, 1, "lookahead");
    assert!(
        errs[0].message.contains("unknown field"),
        "{}",
        errs[0].message
    );

    write(
        t.path(),
        "runtime.toml",
        "cycle_period_us = 0\n[ads]\nnet_id = \"1.2.3.4\"\n",
    );
    let errs = params::check_list_file(&rt);
    assert_eq!(errs.len(), 1, "{errs:#?}");
    assert!(
        errs[0].message.contains("ads.net_id"),
        "{}",
        errs[0].message
    );
    write(t.path(), "runtime.toml", "cycle_period_us = 0\n");
    one_error(
        &errors_of(params::load(&startup)),
        &rt,
        1,
        1,
        "cycle_period_us",
    );

    write(
        t.path(),
        "runtime.toml",
        "cycle_period_us = 250\n[[axes]]\nname = \"X\"\nmax_jerk_mm_per_s3 = 50000.0\n",
    );
    let cfg = params::load(&startup).unwrap();
    assert_eq!(cfg.runtime.cycle_period_us, 250);
    assert_eq!(cfg.runtime.axes.len(), 1);
    assert_eq!(cfg.runtime.axes[0].max_jerk_mm_per_s3, Some(50000.0));
    assert_eq!(cfg.runtime.axes[0].rapid_mm_per_min, 30000.0);
}

#[test]
fn check_decides_list_kind_by_content() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(t.path(), "a.lis", "kanal_anzahl 1\nsda_mds[0] b.lis\n");
    let ch = write(t.path(), "b.lis", "streaming_prog_file s.nc\nfoo 1\n");
    // A start-up list is checked with its channel list.
    let ds = params::check_list_file(&startup);
    assert_eq!(ds.len(), 1, "{ds:#?}");
    assert_eq!(
        (ds[0].file.as_path(), ds[0].line, ds[0].severity),
        (ch.as_path(), 2, Severity::Warning)
    );
    // A channel list alone.
    assert_eq!(params::check_list_file(&ch).len(), 1);
    // A channel list's cache sizes alone do not warn: the start-up list may enable caching.
    write(
        t.path(),
        "b.lis",
        "configuration.decoder.max_cache_size 10\n",
    );
    assert!(params::check_list_file(&ch).is_empty());
    // A missing file is one error.
    let ds = params::check_list_file(&t.path().join("none.lis"));
    assert_eq!(ds.len(), 1);
    assert_eq!(ds[0].severity, Severity::Error);
}

#[test]
fn oversized_list_is_refused_with_a_clear_error() {
    let t = tempfile::tempdir().unwrap();
    let p = t.path().join("huge.lis");
    let f = fs::File::create(&p).unwrap();
    f.set_len(17 * 1024 * 1024).unwrap();
    let e = params::load(&p).unwrap_err();
    assert!(matches!(e, ParamError::File(_)));
    assert!(e.to_string().contains("more than the limit"), "{e}");
}

#[test]
fn latin1_comments_and_crlf_are_tolerated() {
    let t = tempfile::tempdir().unwrap();
    let startup = t.path().join("hochlauf.lis");
    fs::write(
        &startup,
        b"# Kan\xe4le\r\nkanal_anzahl\t1\r\nsda_mds[0]\tch.lis\r\n",
    )
    .unwrap();
    write(t.path(), "ch.lis", CHANNEL);
    let cfg = params::load(&startup).unwrap();
    assert_eq!(cfg.channels.len(), 1);
    assert!(cfg.warnings.is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]
    /// Any text parses to entries and diagnostics without panicking, and every diagnostic
    /// points inside the text.
    #[test]
    fn parser_never_panics(text in "(?s)[ -~\t\r\n\"#(\\[\\]äß.0-9x_-]{0,400}") {
        let (list, diags) = params::list::parse_list(Path::new("p.lis"), &text);
        let lines = text.split('\n').count();
        for d in &diags {
            prop_assert!(d.line >= 1 && d.line <= lines);
            prop_assert!(d.col >= 1);
        }
        for e in &list.entries {
            prop_assert!(e.name_pos.col < e.value_pos.col);
        }
    }
}

#[test]
fn channels_sharing_a_list_report_its_warnings_once() {
    let t = tempfile::tempdir().unwrap();
    let startup = write(
        t.path(),
        "startup.lis",
        "kanal_anzahl 2\nsda_mds[0] ch.lis\nsda_mds[1] ch.lis\n",
    );
    write(t.path(), "ch.lis", "streaming_prog_file s.nc\nfoo 1\n");
    let cfg = params::load(&startup).unwrap();
    assert_eq!(cfg.channels.len(), 2);
    assert_eq!(cfg.channels[1].streaming_prog_file.as_deref(), Some("s.nc"));
    assert_eq!(cfg.warnings.len(), 1, "{:#?}", cfg.warnings);
}

/// An installation's lists in a temp folder: `listen/hochlauf.lis` naming `./listen/…`
/// lists, in Latin-1, with the kernel's constructs.
fn installation(dir: &Path, channel: &str, axis2: &str) -> PathBuf {
    let latin1 = |rel: &str, text: &str| {
        let bytes: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
        let p = dir.join(rel);
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(&p, bytes).unwrap();
        p
    };
    fs::create_dir_all(dir.join("prg")).unwrap();
    latin1(
        "listen/default_mds.lis",
        "getriebe[0].dynamik.a_max 1500 ( P-AXIS-00008 : [mm/s\u{b2}]\n\
         getriebe[0].slope_profil.a_beschl P-AXIS-00008.0\nEnde\n",
    );
    latin1(
        "listen/achsmds1.lis",
        "kopf.achs_nr 1\nkopf.log_achs_name X\nkenngr.swe_pos 15000000 ( P-AXIS-00178 : [0.1um] \
         Positive software limit switch\nkenngr.swe_neg -15000000\n\
         getriebe[0].dynamik.vb_max 500000 ( [um/s]\n\
         getriebe[0].slope_profil.tr_beschl_zu 50000\nEnde\n",
    );
    latin1("listen/achsmds2.lis", axis2);
    latin1("listen/sda_mds1.lis", channel);
    latin1(
        "listen/hochlauf.lis",
        "# Hochlaufliste: Kan\u{e4}le und Achsen\n\
         kanal_anzahl 1 ( P-STUP-00001\n#hand_mds ./listen/hand_mds.lis\n\
         default_achs_mds ./listen/default_mds.lis\n\
         achs_mds[0] ./listen/achsmds1.lis\nachs_mds[1] ./listen/achsmds2.lis\n\
         sda_mds[0] ./listen/sda_mds1.lis\npfad[0].prg[0] ./prg\npfad[0].typ[0] 0x03\n\
         configuration.channel[0].decoder.function FCT_DEFAULT | FCT_USE_CACHED_FILES ( P-STUP-00050\n\
         Ende\n",
    )
}

const AXIS_Y: &str = "kopf.achs_nr 2\nkopf.log_achs_name Y\nkenngr.achs_typ 1\nEnde\n";

#[test]
fn an_installation_in_the_kernels_format_loads_with_its_axes() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let startup = installation(
        d,
        "#spindel[0].range_way 0\ngruppe[0].achse[0].bezeichnung X\n\
         gruppe[0].achse[0].log_achs_nr 1\ngruppe[0].achse[1].bezeichnung Y\n\
         gruppe[0].achse[1].log_achs_nr 2 ( P-CHAN-00035\nstreaming_prog_file s.nc\n\
         m6_prog_file tc.nc\nEnde\n",
        AXIS_Y,
    );
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert!(cfg.warnings.is_empty(), "{:#?}", cfg.warnings);
    // The CNC's working directory is the folder above listen/.
    assert_eq!(cfg.cnc_dir, d);
    let c = &cfg.channels[0];
    assert_eq!(c.list_path, d.join("listen/sda_mds1.lis"));
    assert_eq!(c.search_paths[0].dir, d.join("prg"));
    assert!(c.decoder.cache.enabled);
    assert_eq!(c.implicit.at_m6.as_deref(), Some("tc.nc"));
    assert_eq!(c.implicit.at_start, None);
    let x = &c.axes[0];
    assert_eq!(x.name, "X");
    assert_eq!(x.soft_limit_max_mm, 1500.0);
    assert_eq!(x.soft_limit_min_mm, -1500.0);
    assert_eq!(x.max_velocity_mm_per_min, 30000.0);
    assert_eq!(x.max_acceleration_mm_per_s2, 1500.0);
    // jerk = a_max / the shortest ramp time: 1500 mm/s² / 0.05 s (tr_beschl_zu, and the
    // kernel's default 50000 µs for the other three).
    assert!((x.max_jerk_mm_per_s3.unwrap() - 30000.0).abs() < 1e-6);
    // Y: the kernel's defaults under the default list: vb_max 200000 µm/s = 12000 mm/min,
    // vb_eilgang 166666 µm/s, swe ±100000000 × 0.1 µm = ±10000 mm.
    let y = &c.axes[1];
    assert_eq!(y.name, "Y");
    assert_eq!(y.max_velocity_mm_per_min, 12000.0);
    assert!((y.rapid_mm_per_min - 9999.96).abs() < 1e-9);
    assert_eq!(y.soft_limit_max_mm, 10000.0);
    // Every list read is counted.
    let counts: Vec<(String, usize, usize, usize)> = cfg
        .lists
        .iter()
        .map(|l| {
            (
                l.file.file_name().unwrap().to_string_lossy().into_owned(),
                l.counts.used,
                l.counts.inert,
                l.counts.unknown,
            )
        })
        .collect();
    assert!(
        counts.contains(&("hochlauf.lis".into(), 8, 0, 0)),
        "{counts:?}"
    );
    assert!(
        counts.contains(&("default_mds.lis".into(), 1, 1, 0)),
        "{counts:?}"
    );
    assert!(
        counts.contains(&("sda_mds1.lis".into(), 6, 0, 0)),
        "{counts:?}"
    );

    // P-CHAN-00260 / -00433: a call configured for MDI only is never made (no MDI here).
    installation(
        d,
        "start_init_prog_file i.nc\nstart_init_prog_file_mode MDI\nfinal_prog_file f.nc\n\
         final_prog_file_mode AUTOMATIC | MDI\n",
        AXIS_Y,
    );
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cfg.channels[0].implicit.at_start, None);
    assert_eq!(cfg.channels[0].implicit.at_end.as_deref(), Some("f.nc"));
    installation(d, "final_prog_file_mode SOMETIMES\n", AXIS_Y);
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &d.join("listen/sda_mds1.lis"), 1, 22, "SOMETIMES");

    // Without gruppe[0].achse[j], the axis lists' own names.
    installation(d, "streaming_prog_file s.nc\n", AXIS_Y);
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = cfg.channels[0]
        .axes
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    assert_eq!(names, ["X", "Y"]);
}

#[test]
fn axis_list_problems_name_file_line_and_column() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let chan = |nr: u32, name: &str| {
        format!(
            "gruppe[0].achse[0].bezeichnung X\ngruppe[0].achse[0].log_achs_nr 1\n\
             gruppe[0].achse[1].bezeichnung {name}\ngruppe[0].achse[1].log_achs_nr {nr}\n"
        )
    };
    // A logical axis number no axis list has.
    let startup = installation(d, &chan(7, "Y"), AXIS_Y);
    let errs = errors_of(params::load(&startup));
    one_error(
        &errs,
        &d.join("listen/sda_mds1.lis"),
        4,
        32,
        "kopf.achs_nr 7",
    );
    // A name ncchannel does not drive.
    installation(d, &chan(2, "Q1"), AXIS_Y);
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &d.join("listen/sda_mds1.lis"), 3, 32, "Q1");
    // A spindle as a path axis.
    installation(
        d,
        &chan(2, "Y"),
        "kopf.achs_nr 2\nkenngr.achs_typ ACHSTYP_SPINDEL\n",
    );
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &d.join("listen/sda_mds1.lis"), 4, 32, "spindle");
    // Two axis lists with one logical number (and then no axis 2 for Y).
    installation(d, &chan(2, "Y"), "kopf.achs_nr 1\n");
    let errs = errors_of(params::load(&startup));
    one_error(
        &errs[..1],
        &d.join("listen/hochlauf.lis"),
        6,
        13,
        "kopf.achs_nr 1",
    );
    assert_eq!(errs.len(), 2, "{errs:#?}");
    // Implausible values in an axis list.
    installation(
        d,
        &chan(2, "Y"),
        "kopf.achs_nr 2\ngetriebe[0].dynamik.vb_max 1000\ngetriebe[0].vb_eilgang 2000\n",
    );
    let errs = errors_of(params::load(&startup));
    one_error(&errs, &d.join("listen/achsmds2.lis"), 3, 24, "vb_eilgang");
    // A reference to a parameter no list sets.
    installation(
        d,
        &chan(2, "Y"),
        "kopf.achs_nr 2\ngetriebe[0].dynamik.vb_max P-AXIS-00211.0\n",
    );
    let errs = errors_of(params::load(&startup));
    one_error(
        &errs,
        &d.join("listen/achsmds2.lis"),
        2,
        28,
        "P-AXIS-00211.0",
    );
    // An axis list that cannot be read.
    fs::remove_file(d.join("listen/achsmds2.lis")).unwrap();
    let errs = errors_of(params::load(&startup));
    one_error(
        &errs[..1],
        &d.join("listen/hochlauf.lis"),
        6,
        13,
        "achs_mds[1]",
    );
    assert_eq!(errs.len(), 2, "{errs:#?}");
}

#[test]
fn runtime_toml_names_the_cncs_working_directory() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    installation(&d.join("machine"), "streaming_prog_file s.nc\n", AXIS_Y);
    // The start-up list elsewhere, with runtime.toml beside it naming the installation.
    fs::create_dir_all(d.join("cfg")).unwrap();
    let startup = d.join("cfg/hochlauf.lis");
    fs::copy(d.join("machine/listen/hochlauf.lis"), &startup).unwrap();
    let errs = errors_of(params::load(&startup));
    assert!(errs[0].message.contains("cannot be read"), "{errs:#?}");
    write(d, "cfg/runtime.toml", "cnc_dir = \"../machine\"\n");
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cfg.cnc_dir, d.join("cfg/../machine"));
    assert_eq!(
        cfg.channels[0].list_path,
        d.join("cfg/../machine/listen/sda_mds1.lis")
    );
    // runtime.toml's axes give way to the axis lists, with a warning saying so.
    write(
        d,
        "cfg/runtime.toml",
        "cnc_dir = \"../machine\"\n[[axes]]\nname = \"A\"\n",
    );
    let cfg = params::load(&startup).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cfg.channels[0].axes.len(), 2);
    assert!(
        cfg.warnings
            .iter()
            .any(|w| w.message.contains("[[axes]] is not used")),
        "{:#?}",
        cfg.warnings
    );
}
