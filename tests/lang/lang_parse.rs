//! The block parser against the TF5200 programming manual's syntax: every construct, its canonical text and its errors.

use ncchannel::lang::*;
use ncchannel::vocab::flush::FlushKind;

use super::lang_roundtrip::without_cols;

fn p(line: &str) -> Block {
    parse_block(line).unwrap_or_else(|e| panic!("{line:?}: {e}"))
}

fn err(line: &str) -> (u32, u32) {
    match parse_block(line) {
        Ok(b) => panic!("{line:?} parsed as {b:?}"),
        Err(e) => (e.code, e.col),
    }
}

/// Parse, print canonically, and check the canonical text reads back to the same block and
/// prints to itself.
fn canon(line: &str) -> String {
    let b = p(line);
    let s = b.to_string();
    let again = p(&s);
    assert_eq!(
        without_cols(again.clone()),
        without_cols(b),
        "canonical {s:?} of {line:?} reparses differently"
    );
    assert_eq!(again.to_string(), s);
    s
}

fn words(b: &Block) -> Vec<(char, f64)> {
    let Body::Items(items) = &b.body else {
        panic!("not items: {b:?}")
    };
    items
        .iter()
        .map(|i| match i {
            Item::Word(Word {
                letter,
                value: Value::Num(v),
                ..
            }) => (*letter as char, *v),
            other => panic!("not a literal word: {other:?}"),
        })
        .collect()
}

#[test]
fn plain_motion_block() {
    let b = p("N123 G01 X12.345 Y-6.789 Z.5 F3000\r\n");
    assert_eq!(b.n, Some(123));
    assert_eq!(b.skip_level, None);
    assert_eq!(
        words(&b),
        vec![
            ('G', 1.0),
            ('X', 12.345),
            ('Y', -6.789),
            ('Z', 0.5),
            ('F', 3000.0)
        ]
    );
    let Body::Items(items) = &b.body else {
        unreachable!()
    };
    let cols: Vec<u32> = items
        .iter()
        .map(|i| match i {
            Item::Word(w) => w.col,
            _ => 0,
        })
        .collect();
    assert_eq!(cols, vec![6, 10, 18, 26, 30]);
    assert_eq!(b.to_string(), "N123 G1 X12.345 Y-6.789 Z0.5 F3000");
}

#[test]
fn words_without_blanks_and_lower_case() {
    let b = p("n10g1x10y-2.5f1000");
    assert_eq!(b.n, Some(10));
    assert_eq!(
        words(&b),
        vec![('G', 1.0), ('X', 10.0), ('Y', -2.5), ('F', 1000.0)]
    );
}

#[test]
fn block_skip_levels() {
    assert_eq!(p("/N10 X1").skip_level, Some(1));
    assert_eq!(p("/1 N10 X1").skip_level, Some(1));
    assert_eq!(p("/10 X1").skip_level, Some(10));
    assert_eq!(err("/11 X1"), (20200, 2));
    assert_eq!(err("/0 X1"), (20200, 2));
    assert_eq!(canon("/7 N5 X1"), "/7 N5 X1");
    assert_eq!(canon("/1 X1"), "/ X1");
}

#[test]
fn labels() {
    let b = p("N40: G01 X40");
    assert_eq!(b.n, Some(40));
    assert_eq!(b.label, Some(Label::Number(40)));
    let b = p("[loop_1] G01 X40");
    assert_eq!(b.label, Some(Label::Name("LOOP_1".into())));
    let b = p("N10 [End] ");
    assert_eq!((b.n, b.label), (Some(10), Some(Label::Name("END".into()))));
    assert_eq!(canon("n40:g1x40"), "N40: G1 X40");
}

#[test]
fn empty_and_comment_lines() {
    for line in [
        "",
        "   ",
        "(comment)",
        "; only",
        "( nested ( deeper ) still ) ",
        "(unclosed to the end X10",
        "N030",
        "N22 ( ===== )",
    ] {
        let b = p(line);
        assert_eq!(b.body, Body::Items(vec![]), "{line:?}");
    }
    assert_eq!(
        words(&p("N10 G00 X0 (Move to start) Y1 ; rest X99")),
        vec![('G', 0.0), ('X', 0.0), ('Y', 1.0)]
    );
    assert_eq!(
        words(&p("N36348 X-1.657 Y-17.4202 (Z2.4442")),
        vec![('X', -1.657), ('Y', -17.4202)]
    );
    // A comment cannot sit between an address letter and its value.
    assert_eq!(err("G1 X(a(b)c)5"), (20200, 5));
}

#[test]
fn word_values_as_expressions() {
    let b = p("X[P1*2] Y-[P2] F[SIN[30]*1000]");
    let Body::Items(items) = &b.body else {
        unreachable!()
    };
    assert!(matches!(
        &items[0],
        Item::Word(Word {
            letter: b'X',
            value: Value::Expr(Expr::Binary(BinOp::Mul, _, _)),
            col: 1
        })
    ));
    assert!(matches!(
        &items[1],
        Item::Word(Word {
            letter: b'Y',
            value: Value::Expr(Expr::Unary(UnOp::Neg, _)),
            ..
        })
    ));
    assert_eq!(b.to_string(), "X[P1 * 2] Y[-P2] F[SIN[30] * 1000]");
}

#[test]
fn every_word_letter() {
    for l in "GMHFSTDXYZABCIJKREUVW".chars() {
        let v = if l == 'G' {
            "1"
        } else if matches!(l, 'M' | 'H' | 'T' | 'D') {
            "3"
        } else {
            "2.5"
        };
        let line = format!("{l}{v}");
        let b = p(&line);
        assert_eq!(words(&b).len(), 1, "{line}");
    }
    // Tool and tool offset numbers are whole numbers (900132, value out of range).
    assert_eq!(err("T2.5"), (900132, 1));
    assert_eq!(err("X1 D-1"), (900132, 4));
    assert_eq!(err("Q5"), (20200, 1));
    assert_eq!(err("X10 O5"), (20200, 5));
    assert_eq!(err("X"), (20200, 2));
    assert_eq!(err("X Y1"), (20200, 2));
}

#[test]
fn known_and_unknown_g_and_m() {
    for g in [
        0, 1, 2, 3, 4, 17, 18, 19, 40, 41, 42, 53, 54, 59, 61, 90, 91, 132, 133, 134, 150, 151,
        260, 261,
    ] {
        p(&format!("G{g}"));
    }
    assert_eq!(err("N10 G999 X1"), (20131, 5));
    assert_eq!(err("G1 G7"), (20131, 4));
    // ISG knows G5 (tangential TRC); ncchannel refuses it by name (lang::dialect).
    assert_eq!(err("G1 G5"), (900133, 4));
    assert_eq!(err("G1.5"), (20131, 1));
    assert_eq!(err("G[P1]"), (20131, 1));
    for m in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 17, 29, 30, 10, 99] {
        p(&format!("M{m}"));
    }
    // M and H run to 65,535 (TF5200 user M/H functions).
    p("S1000 M100");
    assert_eq!(err("S1000 M65536"), (20157, 7));
    assert_eq!(err("M3.5"), (20157, 1));
}

#[test]
fn ramp_time_weighting_value() {
    let b = p("G134 50");
    assert_eq!(
        b.body,
        Body::Items(vec![Item::GValue {
            g: 134,
            value: Value::Num(50.0),
            col: 1
        }])
    );
    assert_eq!(p("G134=50").body, b.body);
    assert_eq!(canon("G133 = [P1*2] X1"), "G133=P1 * 2 X1");
    // Without a value G134 stays a plain word.
    assert_eq!(words(&p("G134 X1")), vec![('G', 134.0), ('X', 1.0)]);
}

#[test]
fn assignments() {
    let b = p("P1=10 P5=[P1*2+3] P1[2]=4 P[P1+5]=3 V.L.X=1 v.p.arr[1][P2]=2 @P1=7");
    let Body::Items(items) = &b.body else {
        unreachable!()
    };
    assert_eq!(items.len(), 7);
    let targets: Vec<(VarRef, &Expr, u32)> = items
        .iter()
        .map(|i| match i {
            Item::Assign {
                target, value, col, ..
            } => ((**target).clone(), value, *col),
            Item::AssignP {
                number, value, col, ..
            } => (
                VarRef::P {
                    number: Index::Const(*number),
                    indices: Vec::new(),
                },
                value,
                *col,
            ),
            other => panic!("{other:?}"),
        })
        .collect();
    // `P<n>` is held inline, every other target boxed.
    assert!(matches!(items[0], Item::AssignP { number: 1, .. }));
    assert!(matches!(items[2], Item::Assign { .. }));
    assert!(
        matches!(&targets[0], (VarRef::P { number: Index::Const(1), indices }, Expr::Num(v), 1) if indices.is_empty() && *v == 10.0)
    );
    assert!(matches!(
        &targets[3].0,
        VarRef::P {
            number: Index::Expr(_),
            ..
        }
    ));
    assert!(
        matches!(&targets[5].0, VarRef::V { scope: VScope::Program, name, indices } if name == "ARR" && indices.len() == 2)
    );
    assert!(matches!(targets[6].0, VarRef::CycleParam(1)));
    assert_eq!(
        b.to_string(),
        "P1=10 P5=P1 * 2 + 3 P1[2]=4 P[P1 + 5]=3 V.L.X=1 V.P.ARR[1][P2]=2 @P1=7"
    );
    assert_eq!(canon("P1 = P2 + 3 X[P1]"), "P1=P2 + 3 X[P1]");
    assert_eq!(err("P1 10"), (20200, 4));
    assert_eq!(err("V.Q.X=1"), (20200, 3));
}

#[test]
fn control_statements() {
    use Control::*;
    let cases: Vec<(&str, Control)> = vec![
        ("$IF P1 == 10", If(parse_expr("P1==10").unwrap())),
        ("$ELSEIF P1 > 2", ElseIf(parse_expr("P1>2").unwrap())),
        ("$else", Else),
        ("$ENDIF", EndIf),
        ("$SWITCH P1", Switch(parse_expr("P1").unwrap())),
        ("$CASE 5", Case(Expr::Num(5.0))),
        ("$DEFAULT", Default),
        ("$BREAK", Break),
        ("$ENDSWITCH", EndSwitch),
        ("$ENDFOR", EndFor),
        ("$WHILE P1 < 3", While(parse_expr("P1<3").unwrap())),
        ("$ENDWHILE", EndWhile),
        ("$DO", Do),
        ("$ENDDO P1 < 3", EndDo(parse_expr("P1<3").unwrap())),
        ("$REPEAT", Repeat),
        ("$UNTIL P1 >= 3", Until(parse_expr("P1>=3").unwrap())),
        ("$CONTINUE", Continue),
        ("$GOTO N40", Goto(GotoTarget::Number(40))),
        ("$GOTO [label_1]", Goto(GotoTarget::Name("LABEL_1".into()))),
        (
            "$IF P1 == 1 $GOTO [END]",
            IfGoto(parse_expr("P1==1").unwrap(), GotoTarget::Name("END".into())),
        ),
    ];
    for (line, want) in cases {
        let b = p(&format!("N5 {line} ; comment"));
        assert_eq!(b.body, Body::Control(Box::new(want)), "{line}");
        canon(line);
    }
    let b = p("$FOR P1 = 0, 10, 2");
    assert!(matches!(&b.body, Body::Control(c) if matches!(**c, For { step: Some(_), .. })));
    assert_eq!(b.to_string(), "$FOR P1=0, 10, 2");
    assert!(matches!(
        &p("$FOR V.L.I=1,P2").body,
        Body::Control(c) if matches!(**c, For { step: None, .. })
    ));
    assert_eq!(err("$FOOBAR"), (20209, 1));
    assert_eq!(err("N10 $IF P1 G1"), (20200, 12));
    assert_eq!(err("N10 $ENDIF X1"), (20200, 12));
    // A $ statement after other words: TF5200 diagnosis ID 20206.
    assert_eq!(err("X1 $ENDIF"), (20206, 4));
    assert_eq!(err("G1 X10 $IF P1 == 1"), (20206, 8));
    assert_eq!(err("$GOTO 40"), (20200, 7));
}

#[test]
fn hash_commands() {
    use Command::*;
    let cases: Vec<(&str, Command)> = vec![
        ("#FLUSH", Flush(FlushKind::Stop)),
        ("#FLUSH CONTINUE", Flush(FlushKind::Continue)),
        ("#flush wait", Flush(FlushKind::Wait)),
        (
            "#CACHE LOAD[FILE=Laser_on.cyc]",
            CacheLoad {
                file: "Laser_on.cyc".into(),
            },
        ),
        (
            "#CACHE CLEAR [ FILE = Macro.cyc ]",
            CacheClear {
                file: "Macro.cyc".into(),
            },
        ),
        ("#CACHE CLEAR ALL", CacheClearAll),
        ("#COMMENT BEGIN", CommentBegin),
        ("#COMMENT END", CommentEnd),
        ("#SPLINE ON", Spline(SplineCommand::On)),
        ("#SPLINE OFF", Spline(SplineCommand::Off)),
        ("#SPLINE TYPE AKIMA", Spline(SplineCommand::TypeAkima)),
        ("#SPLINE TYPE BSPLINE", Spline(SplineCommand::TypeBspline)),
        (
            "#HSC ON [OPMODE 2]",
            Hsc {
                on: true,
                options: "OPMODE 2".into(),
            },
        ),
        (
            "#HSC OFF",
            Hsc {
                on: false,
                options: String::new(),
            },
        ),
        (
            "#CONTOUR MODE [DEV PATH_DEV 0.1 [P1]]",
            ContourMode {
                options: "DEV PATH_DEV 0.1 [P1]".into(),
            },
        ),
        ("#VAR", Var),
        ("#ENDVAR", EndVar),
    ];
    for (line, want) in cases {
        let b = p(&format!("N1260 {line} ; refresh cache"));
        assert_eq!(b.body, Body::Command(Box::new(want)), "{line}");
        canon(line);
    }
    assert_eq!(err("#FOO"), (20209, 1));
    assert_eq!(err("N10 #NOSUCH [\"x\"]"), (20209, 5));
    assert_eq!(err("#FLUSH X1"), (20200, 8));
    // A # command after other words: TF5200 diagnosis ID 20207, whose example this is.
    assert_eq!(err("G1 #FLUSH"), (20207, 4));
    assert_eq!(err("G1 X10 F100 #TIME 8.15"), (20207, 13));
    // A call after other words stays the general syntax error.
    assert_eq!(err("X1 L sub.nc"), (20200, 4));
}

#[test]
fn cache_errors() {
    assert_eq!(err("#CACHE"), (21560, 7));
    assert_eq!(err("#CACHE FETCH[FILE=a]"), (21560, 8));
    assert_eq!(err("#CACHE LOAD"), (21560, 12));
    assert_eq!(err("#CACHE LOAD[]"), (21560, 13));
    assert_eq!(err("#CACHE LOAD[FILE=]"), (21560, 18));
    assert_eq!(err("#CACHE LOAD[NAME=a]"), (21560, 13));
    assert_eq!(err("#CACHE LOAD[FILE=a"), (21560, 19));
    assert_eq!(err("#CACHE LOAD[FILE=a] X1"), (21560, 21));
    assert_eq!(err("#CACHE LOAD[FILE=a FILE=b]"), (21561, 20));
    assert_eq!(err("#CACHE LOAD[FILE=a][FILE=b]"), (21561, 20));
    assert_eq!(err("#CACHE CLEAR ALL [FILE=b]"), (21561, 18));
}

#[test]
fn calls_and_heads() {
    assert_eq!(
        p("N40 L streaming.nc").body,
        Body::Call(Box::new(Call::Global {
            file: "streaming.nc".into()
        }))
    );
    assert_eq!(
        p("LL Sub_1").body,
        Body::Call(Box::new(Call::Local {
            name: "SUB_1".into()
        }))
    );
    let b = p("N3021 L CYCLE [NAME=Laser_on.cyc @P1=0 @P2=[P5*2]]");
    let Body::Call(call) = &b.body else {
        panic!("{b:?}")
    };
    let Call::Cycle {
        name,
        local: false,
        params,
    } = &**call
    else {
        panic!("{b:?}")
    };
    assert_eq!(name, "Laser_on.cyc");
    assert_eq!(params.len(), 2);
    assert_eq!(params[0], (1, CycleArg::Expr(Expr::Num(0.0))));
    assert_eq!(
        b.to_string(),
        "N3021 L CYCLE [NAME=Laser_on.cyc @P1=0 @P2=P5 * 2]"
    );
    assert_eq!(
        p("%streaming-spline").body,
        Body::ProgramHead(Box::new(ProgramHead {
            name: "streaming-spline".into(),
            local: false,
            title: String::new()
        }))
    );
    assert_eq!(
        p("%L sub1").body,
        Body::ProgramHead(Box::new(ProgramHead {
            name: "SUB1".into(),
            local: true,
            title: String::new()
        }))
    );
    canon("%L SUB1");
    canon("%main (head)");
    assert_eq!(err("L streaming.nc X10"), (20200, 16));
    assert_eq!(err("L CYCLE [NAME=a.cyc] G1"), (20200, 22));
    assert_eq!(err("L CYCLE [@P1=0]"), (20200, 9));
    assert_eq!(err("L CYCLE [NAME=a @P1=0 @P1=2]"), (20200, 23));
    assert_eq!(err("G1 L sub.nc"), (20200, 4));
    assert_eq!(err("Lsub.nc"), (20200, 1));
}

#[test]
fn line_ends_and_length() {
    assert_eq!(p("X1\r\n"), p("X1"));
    assert_eq!(p("X1\n"), p("X1"));
    assert_eq!(p("X1\r"), p("X1"));
    assert_eq!(err("X1\rY2"), (20200, 3));
    let long = format!("X1 ({})", "c".repeat(3995));
    assert_eq!(long.len(), 4000);
    p(&long);
    let too_long = format!("X1 ({})", "c".repeat(4000));
    assert_eq!(err(&too_long), (20200, 4001));
    // Characters, not bytes: 3000 umlauts are 6000 bytes but fit.
    p(&format!("X1 ({})", "ä".repeat(3000)));
}

#[test]
fn columns_count_characters() {
    assert_eq!(err("(äöü) G999"), (20131, 7));
}

#[test]
fn comment_end_detection() {
    assert!(is_comment_end("#COMMENT END"));
    assert!(is_comment_end("  #comment   end  \r\n"));
    assert!(is_comment_end("N10 #COMMENT END ; done"));
    assert!(is_comment_end("/2 N10 #COMMENT END"));
    assert!(!is_comment_end("#COMMENT ENDX"));
    assert!(!is_comment_end("#COMMENTEND"));
    assert!(!is_comment_end("(#COMMENT END)"));
    assert!(!is_comment_end("G1 X1"));
}

#[test]
fn var_declarations() {
    let d = parse_var_declaration("V.L.COUNT = 5\r\n").unwrap();
    assert_eq!(
        d,
        VarDecl {
            scope: VScope::Local,
            name: "COUNT".into(),
            dims: vec![],
            ty: None,
            init: Some(Expr::Num(5.0)),
            text: None,
            values: vec![]
        }
    );
    let d = parse_var_declaration("  v.p.table[10][3] ; grid").unwrap();
    assert_eq!(
        (
            d.scope,
            d.name.as_str(),
            d.dims.as_slice(),
            d.init.is_none()
        ),
        (VScope::Program, "TABLE", &[10u32, 3][..], true)
    );
    assert_eq!(d.to_string(), "V.P.TABLE[10][3]");
    assert_eq!(parse_var_declaration("V.E.X = 1").unwrap_err().code, 20200);
    assert_eq!(parse_var_declaration("V.L.A[0]").unwrap_err().code, 20200);
    assert_eq!(parse_var_declaration("G1 X1").unwrap_err().col, 1);
    assert_eq!(parse_var_declaration("V.L.A = 1 X").unwrap_err().col, 11);
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let deep = format!("X{}1{}", "[".repeat(1000), "]".repeat(1000));
    assert_eq!(parse_block(&deep).unwrap_err().code, 20200);
    let minus = format!("P1={}1", "-".repeat(3000));
    assert_eq!(parse_block(&minus).unwrap_err().code, 20200);
    // A flat chain is built without recursion but its tree is as high as it is long: beyond
    // 256 operators it is refused, below it is parsed, printed and evaluated.
    let too_long = format!("P1={}1", "1+".repeat(300));
    assert_eq!(parse_block(&too_long).unwrap_err().code, 20200);
    let chain = format!("P1={}1", "1+".repeat(250));
    let b = p(&chain);
    let Body::Items(items) = &b.body else {
        unreachable!()
    };
    let Item::AssignP { value, .. } = &items[0] else {
        unreachable!()
    };
    struct NoVars;
    impl Vars for NoVars {
        fn get(&self, _: &VarKey<'_>) -> Option<f64> {
            None
        }
    }
    assert_eq!(eval(value, &NoVars), Ok(251.0));
    assert!(b.to_string().len() > 1000);
    // Every 4000-character shape stays within the bound: the worst, a right-leaning power
    // tower and a nest of functions, are refused or parsed, never overflow.
    let tower = format!("P1={}2", "2**".repeat(1300));
    assert_eq!(parse_block(&tower).unwrap_err().code, 20200);
    let funcs = format!("P1={}1{}", "ABS[".repeat(700), "]".repeat(700));
    assert_eq!(parse_block(&funcs).unwrap_err().code, 20200);
}

#[test]
fn a_reused_item_list_parses_as_a_new_one() {
    let lines = [
        "N10 G01 X1 Y2 Z3 F1000",
        "P1=5 P2=[P1*2] P3[1]+=2 V.L.A=1",
        "#FLUSH",
        "",
        "( a comment only )",
        "$IF P1 == 5",
        "X1",
    ];
    let long = (0..40)
        .map(|k| format!("P{k}={k}"))
        .collect::<Vec<_>>()
        .join(" ");
    let longer = (0..70)
        .map(|k| format!("P{k}={k}"))
        .collect::<Vec<_>>()
        .join(" ");
    // A list left over from another block, with items still in it and room for few or many.
    let dirty = || {
        let Body::Items(items) = parse_block("X1 Y2 Z3").unwrap().body else {
            unreachable!()
        };
        items
    };
    for line in lines
        .iter()
        .copied()
        .chain([long.as_str(), longer.as_str()])
    {
        let fresh = parse_block(line);
        for spare in [Vec::new(), dirty(), Vec::with_capacity(ITEM_LIST_CAPACITY)] {
            assert_eq!(parse_block_reusing(line, spare), fresh, "{line}");
        }
    }
    // A list grown past what is kept is given up; an ordinary one comes back empty.
    let mut b = parse_block(&longer).unwrap();
    assert!(b.take_items().is_none());
    let mut b = parse_block("X1 Y2").unwrap();
    assert_eq!(b.take_items().map(|l| l.len()), Some(0));
    assert!(parse_block("#FLUSH").unwrap().take_items().is_none());
}
