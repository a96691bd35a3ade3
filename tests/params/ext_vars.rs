//! The list of external variables the start-up list names (`ve_var[i]`, TF5200 Start-up list
//! P-STUP-00146; its entries TF5200 External variables P-EXTV-00001 … P-EXTV-00022): a
//! program writes and reads what it declares — scalars, an array, structure members, strings
//! — in their types, and is refused with the kernel's ids what it does not; `#FILENAME
//! [MSG=V.E.x]` reads its string; `check` names a bad entry by file, line and column.

use std::process::Command;

use crate::support::Rig;

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ext_vars/ve.lis");

/// A channel whose start-up list names the fixture list.
fn rig() -> Rig {
    let rig = Rig::new();
    std::fs::copy(FIXTURE, rig.dir.path().join("params/ve.lis")).unwrap();
    let startup = std::fs::read_to_string(rig.startup()).unwrap();
    std::fs::write(rig.startup(), format!("{startup}ve_var[0] ve.lis\n")).unwrap();
    rig
}

fn messages(r: &crate::support::RunResult) -> Vec<String> {
    r.of("message")
        .iter()
        .map(|m| m["text"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_program_writes_and_reads_each_kind_of_declared_variable() {
    let rig = rig();
    rig.program(
        "ve.nc",
        "%ve\n\
         N10 V.E.COUNT = -3.6\n\
         N20 V.E.LAMP = 1\n\
         N30 V.E.FARBE[0] = 7\n\
         N40 V.E.FARBE[2] = V.E.FARBE[0] * 2\n\
         N50 V.E.Sch.Preflow = 3.25\n\
         N60 V.E.UserInteraction.Message = \"Insert tool\"\n\
         N70 V.E.TEACH_FILE_NAME = \"teach_01.nc\"\n\
         N80 #MSG [\"%d %d %d %d %.2f\", V.E.COUNT, V.E.LAMP, V.E.FARBE[0], V.E.FARBE[2], V.E.SCH.PREFLOW]\n\
         N90 #MSG [\"%s / %s\", V.E.USERINTERACTION.MESSAGE, V.E.teach_file_name]\n\
         N100 $IF V.E.UserInteraction.Message == \"Insert tool\"\n\
         N110 #MSG [\"equal\"]\n\
         N120 $ENDIF\n\
         N130 #FILENAME [MSG=V.E.TEACH_FILE_NAME]\n\
         N140 #MSG [\"unset: %d\", V.E.FARBE[1]]\n\
         M30\n",
    );
    let r = rig.run("ve.nc", None, 5_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.of("error"));
    // SGN16 rounds -3.6 to -4; FARBE[1] was never written: 0, as the kernel clears them.
    assert_eq!(
        messages(&r),
        [
            "-4 1 7 14 3.25",
            "Insert tool / teach_01.nc",
            "equal",
            "unset: 0"
        ]
    );
}

/// One line after `%t` on the fixture's channel: the id it is refused with.
fn refused_with(line: &str) -> Vec<u64> {
    let rig = rig();
    rig.program("t.nc", &format!("%t\nN10 {line}\nM30\n"));
    rig.run("t.nc", None, 5_000).error_codes()
}

#[test]
fn what_the_list_does_not_allow_is_refused_with_the_kernels_ids() {
    for (line, code) in [
        // Not declared (the kernel's error list: unknown variable).
        ("V.E.NOPE = 1", 20196),
        ("V.P.X = V.E.NOPE", 20196),
        ("V.E.SCH = 1", 20196),
        ("#FILENAME [MSG=V.E.NOPE]", 20196),
        // Index outside the declared array (21928).
        ("V.E.FARBE[3] = 1", 21928),
        ("V.P.X = V.E.FARBE[3]", 21928),
        // Outside the type's range (20847): SGN16, BOOLEAN.
        ("V.E.COUNT = 40000", 20847),
        ("V.E.LAMP = 2", 20847),
        // READ_ONLY written (20100), WRITE_ONLY read (20097) by a program.
        ("V.E.USERINTERACTION.PLC_READY = 1", 20100),
        ("V.P.X = V.E.SECRET", 20097),
        // The wrong kind of value: a string into a number, a number into a string.
        ("V.E.COUNT = \"x\"", 900008),
        ("V.E.TEACH_FILE_NAME = 5", 900009),
        ("#FILENAME [MSG=V.E.COUNT]", 900009),
        // A VSTRING of size 5 (P-EXTV-00008) holds 4 characters and the NUL (21462).
        ("V.E.SHORT = \"abcde\"", 21462),
    ] {
        assert_eq!(refused_with(line), [code], "{line}");
    }
    // A WRITE_ONLY variable is written, a READ_ONLY one read.
    assert!(refused_with("V.E.SECRET = 1").is_empty());
    assert!(refused_with("V.P.X = V.E.USERINTERACTION.PLC_READY").is_empty());
    assert!(refused_with("V.E.SHORT = \"abcd\"").is_empty());
    // STRING holds 127 characters with use_extended_string_var (P-EXTV-00022), 20 without:
    // the longest string an expression makes (126) fits.
    assert!(refused_with(&format!("V.E.TEACH_FILE_NAME = \"{}\"", "x".repeat(126))).is_empty());
}

#[test]
fn without_a_list_v_e_variables_stay_free() {
    let rig = Rig::new();
    rig.program(
        "free.nc",
        "%free\nN10 V.E.ANY.MEMBER = 2\nN20 V.E.S = \"text\"\n\
         N30 #MSG [\"%d %s\", V.E.ANY.MEMBER, V.E.S]\nN40 #FILENAME [MSG=V.E.S]\nM30\n",
    );
    let r = rig.run("free.nc", None, 5_000);
    assert!(r.error_codes().is_empty(), "{:?}", r.of("error"));
    assert_eq!(messages(&r), ["2 text"]);
}

fn check(path: &std::path::Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .arg(path)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

#[test]
fn check_names_bad_entries_by_file_line_and_column() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("ve.lis");
    std::fs::write(
        &p,
        "var[0].name OK\nvar[0].type UNS08\n\
         var[1].name 9LIVES\n\
         var[2].name T\nvar[2].type FLOAT\n\
         var[3].name OK\n\
         var[4].name A\nvar[4].array_elements -1\n\
         var[5].name R\nvar[5].access_rights SOMETIMES\n\
         var[6].name L\nvar[6].type LOOP\n\
         struct[0].name LOOP\nstruct[0].element[0].name IN\nstruct[0].element[0].type LOOP\n\
         var[7].colour red\n",
    )
    .unwrap();
    let (code, out) = check(&p);
    assert_eq!(code, 1, "{out}");
    for want in [
        "ve.lis:3:13: error: var[1].name: `9LIVES` is not a name",
        "ve.lis:5:13: error: var[2].type: unknown type FLOAT",
        "ve.lis:6:13: error: var[3].name: OK is already declared on line 1",
        "ve.lis:8:23: error: var[4].array_elements: must not be negative",
        "ve.lis:10:22: error: var[5].access_rights: READ_WRITE, READ_ONLY, WRITE_ONLY or INHERIT_ACCESS expected",
        "ve.lis:15:27: error: struct[0].element[0].type: structures nested more than 8 deep",
        "ve.lis:16:1: warning: unknown parameter var[7].colour",
    ] {
        assert!(out.contains(want), "`{want}` in:\n{out}");
    }
    assert!(out.contains("external variable list"), "{out}");
}

#[test]
fn the_start_up_list_refuses_a_channel_whose_list_is_missing() {
    let rig = Rig::new();
    let startup = std::fs::read_to_string(rig.startup()).unwrap();
    std::fs::write(rig.startup(), format!("{startup}ve_var[0] missing.lis\n")).unwrap();
    let (code, out) = check(&rig.startup());
    assert_eq!(code, 1, "{out}");
    let line = std::fs::read_to_string(rig.startup())
        .unwrap()
        .lines()
        .count();
    assert!(
        out.contains(&format!(
            "startup.lis:{line}:11: error: ve_var[0]: external variable list"
        )),
        "{out}"
    );
}
