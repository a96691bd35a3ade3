//! Expression precedence, functions and evaluation errors, through the parser.

use std::collections::HashMap;

use ncchannel::lang::*;

#[derive(Default)]
struct Store(HashMap<String, f64>);

impl Vars for Store {
    fn get(&self, key: &VarKey<'_>) -> Option<f64> {
        self.0.get(&key.to_string()).copied()
    }
}

fn store(pairs: &[(&str, f64)]) -> Store {
    Store(pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect())
}

fn ev(text: &str) -> f64 {
    ev_with(text, &Store::default())
}

fn ev_with(text: &str, vars: &Store) -> f64 {
    let e = parse_expr(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    eval(&e, vars).unwrap_or_else(|e| panic!("{text}: {e}"))
}

fn ev_err(text: &str) -> u32 {
    let e = parse_expr(text).unwrap();
    eval(&e, &Store::default()).unwrap_err().code()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn arithmetic_precedence() {
    assert_eq!(ev("2 + 3 * 4"), 14.0);
    assert_eq!(ev("[2 + 3] * 4"), 20.0);
    assert_eq!(ev("10 - 4 - 3"), 3.0, "left associative");
    assert_eq!(ev("24 / 4 / 2"), 3.0);
    assert_eq!(ev("2 ** 3 ** 2"), 512.0, "** is right associative");
    assert_eq!(ev("-2 ** 2"), -4.0, "** binds tighter than unary minus");
    assert_eq!(ev("[-2] ** 2"), 4.0);
    assert_eq!(ev("2 ** -1"), 0.5);
    assert_eq!(ev("7 MOD 3 + 1"), 2.0);
    assert_eq!(ev("-7 mod 3"), -1.0);
    assert_eq!(ev("2 * -3"), -6.0);
    assert_eq!(ev("3 - -2"), 5.0);
}

#[test]
fn comparison_and_logic_precedence() {
    assert_eq!(ev("1 + 1 == 2"), 1.0, "+ before ==");
    assert_eq!(ev("1 < 2 && 3 > 4"), 0.0);
    assert_eq!(ev("1 < 2 || 3 > 4"), 1.0);
    assert_eq!(ev("1 || 0 && 0"), 1.0, "&& binds tighter than ||");
    assert_eq!(ev("1 XOR 1 || 1"), 1.0, "XOR binds tighter than ||");
    assert_eq!(ev("0 && 1 XOR 1"), 1.0, "&& binds tighter than XOR");
    assert_eq!(ev("1 AND 1 OR 0"), 1.0);
    assert_eq!(ev("NOT 0"), 1.0);
    assert_eq!(ev("NOT 0.7"), 0.0, "0.7 is true");
    assert_eq!(ev("NOT 0.4"), 1.0, "0.4 is false");
    assert_eq!(ev("2 != 3"), 1.0);
    assert_eq!(ev("2 <> 2"), 0.0);
    assert_eq!(ev("2 <= 2"), 1.0);
    assert_eq!(ev("3 >= 4"), 0.0);
}

#[test]
fn bitwise_precedence() {
    assert_eq!(ev("6 & 3"), 2.0);
    assert_eq!(ev("6 | 3"), 7.0);
    assert_eq!(ev("6 ^ 3"), 5.0);
    assert_eq!(ev("1 | 6 & 3"), 3.0, "& binds tighter than |");
    assert_eq!(ev("1 | 6 ^ 3"), 5.0, "^ binds tighter than |");
    assert_eq!(ev("4 ^ 6 & 3"), 6.0, "& binds tighter than ^");
    assert_eq!(ev("1 == 1 & 3"), 1.0, "comparison binds tighter than &");
    assert_eq!(ev("INV 0"), -1.0);
    assert_eq!(ev("INV 5 & 7"), 2.0);
}

#[test]
fn functions_in_degrees() {
    assert!(close(ev("SIN[30]"), 0.5));
    assert_eq!(ev("COS[90]"), 0.0);
    assert_eq!(ev("SIN[180]"), 0.0);
    assert_eq!(ev("COS[-180]"), -1.0);
    assert!(close(ev("TAN[45]"), 1.0));
    assert!(close(ev("ASIN[0.5]"), 30.0));
    assert!(close(ev("ACOS[0]"), 90.0));
    assert!(close(ev("ATAN[1]"), 45.0));
    assert!(close(ev("ATAN2[1, -1]"), 135.0));
    assert_eq!(ev("ABS[-3]"), 3.0);
    assert_eq!(ev("SQR[3]"), 9.0);
    assert_eq!(ev("SQRT[16]"), 4.0);
    assert!(close(ev("EXP[1]"), std::f64::consts::E));
    assert!(close(ev("LN[EXP[2]]"), 2.0));
    assert_eq!(ev("LOG[1000]"), 3.0);
    assert_eq!(ev("INT[-2.7]"), -2.0);
    assert!(close(ev("FRACT[2.75]"), 0.75));
    assert_eq!(ev("ROUND[2.5]"), 3.0);
    assert_eq!(ev("ROUND[-2.5]"), -3.0);
    assert_eq!(ev("FLOOR[-2.5]"), -3.0);
    assert_eq!(ev("CEIL[2.1]"), 3.0);
    assert_eq!(ev("pi"), std::f64::consts::PI);
    assert_eq!(ev("TRUE + FALSE"), 1.0);
    assert_eq!(ev("sin[2*45] + cos [ 0 ]"), 2.0);
}

#[test]
fn function_syntax_errors() {
    assert_eq!(parse_expr("ATAN2[1]").unwrap_err().code, 20200);
    assert_eq!(parse_expr("SIN[1, 2]").unwrap_err().code, 20200);
    assert_eq!(parse_expr("FOO[1]").unwrap_err().col, 1);
    assert_eq!(parse_expr("SIN 30").unwrap_err().col, 5);
    assert_eq!(parse_expr("1 +").unwrap_err().col, 4);
    assert_eq!(parse_expr("[1 + 2").unwrap_err().col, 7);
    assert_eq!(parse_expr("MODE").unwrap_err().code, 20200);
}

#[test]
fn evaluation_errors_have_numbers() {
    assert_eq!(ev_err("1 / 0"), 20396);
    assert_eq!(ev_err("1 MOD 0"), 20396);
    assert_eq!(ev_err("SQRT[-1]"), 20398);
    assert_eq!(ev_err("ACOS[1.5]"), 900003);
    assert_eq!(ev_err("ASIN[-2]"), 900003);
    assert_eq!(ev_err("LN[0]"), 20399);
    assert_eq!(ev_err("P7 + 1"), 900005);
    assert_eq!(ev_err("P[0.5]"), 900006);
    assert_eq!(ev_err("P[-1]"), 900006);
    assert_eq!(ev_err("EXP[1000]"), 900007);
    assert_eq!(ev_err("TAN[90]"), 900007);
    let e = parse_expr("V.L.MISSING").unwrap();
    let err = eval(&e, &Store::default()).unwrap_err();
    assert_eq!(err.to_string(), "undefined variable V.L.MISSING");
}

#[test]
fn variables_and_indices_resolve() {
    let vars = store(&[
        ("P1", 2.0),
        ("P7", 70.0),
        ("P3[2]", 32.0),
        ("V.L.COUNT", 5.0),
        ("V.P.GRID[1][2]", 12.0),
        ("@P1", 0.25),
    ]);
    assert_eq!(ev_with("P1 * 3", &vars), 6.0);
    assert_eq!(ev_with("P[P1 + 5]", &vars), 70.0, "indirect P[P1+5] is P7");
    assert_eq!(ev_with("P3[P1]", &vars), 32.0);
    assert_eq!(
        ev_with("P[3*0.1*10][2]", &vars),
        32.0,
        "near-integers index"
    );
    assert_eq!(ev_with("v.l.count + 1", &vars), 6.0);
    assert_eq!(ev_with("V.P.GRID[P1 - 1][P1]", &vars), 12.0);
    assert_eq!(ev_with("@P1 * 4", &vars), 1.0);

    let target = parse_block("P[P1+5][P1]=1").unwrap();
    let Body::Items(items) = &target.body else {
        panic!()
    };
    let Item::Assign { target, .. } = &items[0] else {
        panic!()
    };
    assert_eq!(
        resolve(target, &vars),
        Ok(VarKey::P {
            number: 7,
            indices: vec![2]
        })
    );
    let v = VarRef::V {
        scope: VScope::Local,
        name: "X".into(),
        indices: vec![],
    };
    assert_eq!(
        resolve(&v, &vars),
        Ok(VarKey::V {
            scope: VScope::Local,
            name: "X",
            indices: vec![]
        })
    );
}

#[test]
fn truth_and_case_tolerances() {
    assert!(is_true(0.5));
    assert!(is_true(-0.5));
    assert!(!is_true(0.49));
    assert!(!is_true(-0.4999));
    assert!(case_matches(5.0, 5.0009));
    assert!(!case_matches(5.0, 5.001));
    assert!(case_matches(-1.0, -0.9995));
}

/// A store with strings beside numbers, as the decoder's `STRING[n]` variables are.
#[derive(Default)]
struct Texts(HashMap<String, String>);

impl Vars for Texts {
    fn get(&self, _key: &VarKey<'_>) -> Option<f64> {
        None
    }
    fn get_str(&self, key: &VarKey<'_>) -> Option<&str> {
        self.0.get(&key.to_string()).map(String::as_str)
    }
}

fn val(text: &str) -> Val {
    let vars = Texts(
        [
            ("V.E.STR1", "Hello world! How are you?"),
            ("V.E.STR2", "How"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect(),
    );
    let e = parse_expr(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    eval_value(&e, &vars).unwrap_or_else(|e| panic!("{text}: {e}"))
}

fn s(t: &str) -> Val {
    Val::Str(t.to_string())
}

fn val_err(text: &str) -> u32 {
    let e = parse_expr(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    eval_value(&e, &Texts::default()).unwrap_err().code()
}

/// The examples of TF5200 "Operations for character strings", and DELETE as diagnosis
/// 21545's example calls it.
#[test]
fn string_functions_give_the_manuals_results() {
    assert_eq!(val("\"Hello\" + \" world!\""), s("Hello world!"));
    assert_eq!(val("LEFT[\"Hello world!\", 5]"), s("Hello"));
    assert_eq!(val("MID[\"How are you?\", 3, 5]"), s("are"));
    assert_eq!(
        val("RIGHT[\"Hello world! How are you?\", 12]"),
        s("How are you?")
    );
    assert_eq!(val("LEN[\"Hello world! How are you?\"]"), Val::Num(25.0));
    assert_eq!(val("ORD[\"Hello world!\", 1]"), Val::Num(72.0));
    assert_eq!(val("ORD[\"Hello world!\", 7]"), Val::Num(119.0));
    assert_eq!(val("ORD[\"Hello\"]"), Val::Num(72.0));
    assert_eq!(val("FIND[V.E.STR1, V.E.STR2]"), Val::Num(14.0));
    assert_eq!(
        val("FIND[V.E.STR1, \"how\"]"),
        Val::Num(0.0),
        "case-sensitive"
    );
    assert_eq!(val("DELETE[\"Hello world!\", 7, 5]"), s("Hell!"));
    assert_eq!(val("\"abc\" == \"abc\""), Val::Num(1.0));
    assert_eq!(val("\"abc\" != \"abC\""), Val::Num(1.0));
    assert_eq!(val("LEFT[V.E.STR2, 2] + \"!\" == \"Ho!\""), Val::Num(1.0));
    // Numbers stay numbers.
    assert_eq!(val("2 + 3"), Val::Num(5.0));
    // Characters, not bytes.
    assert_eq!(val("LEN[\"Größe\"]"), Val::Num(5.0));
    assert_eq!(val("MID[\"Größe\", 2, 3]"), s("öß"));
}

#[test]
fn string_errors_are_the_kernels() {
    assert_eq!(val_err("DELETE[\"Hello world!\", 7, 100]"), 21545);
    assert_eq!(val_err("MID[\"abc\", 3, 2]"), 21545, "past the end");
    assert_eq!(val_err("LEFT[\"abc\", -1]"), 21545);
    assert_eq!(val_err("ORD[\"abc\", 4]"), 21545);
    assert_eq!(val_err("\"a\" - \"b\""), 21458);
    assert_eq!(val_err("\"a\" < \"b\""), 21458);
    assert_eq!(val_err("\"a\" + 1"), 21458);
    assert_eq!(val_err("LEN[5]"), 900009);
    let long = "x".repeat(100);
    assert_eq!(val_err(&format!("\"{long}\" + \"{long}\"")), 21870);
    // A literal longer than a string may be is refused by the parser.
    let e = parse_expr(&format!("\"{}\"", "y".repeat(127))).unwrap_err();
    assert_eq!((e.code, e.col), (21870, 1));
    // Where a number is needed, a string is 900008.
    for text in ["\"abc\"", "LEFT[\"abc\", 1]", "\"a\" + \"b\"", "SIN[\"a\"]"] {
        assert_eq!(
            eval(&parse_expr(text).unwrap(), &Texts::default())
                .unwrap_err()
                .code(),
            900008,
            "{text}"
        );
    }
    assert_eq!(ev("LEN[\"abc\"] * 2"), 6.0);
}

/// A string holds what a comment would start (`;`, `(`): the quotes come first.
#[test]
fn quoted_text_is_not_a_comment() {
    for (t, printed) in [
        ("V.L.S = \"a;b\"", "V.L.S=\"a;b\""),
        ("V.L.S = \"a (b) c\" ; comment", "V.L.S=\"a (b) c\""),
        ("$IF V.L.S == \"x(y)\"", "$IF V.L.S == \"x(y)\""),
        ("V.L.S = \"\"", "V.L.S=\"\""),
    ] {
        let b = parse_block(t).unwrap_or_else(|e| panic!("{t}: {e}"));
        assert_eq!(b.to_string(), printed, "{t}");
    }
}
