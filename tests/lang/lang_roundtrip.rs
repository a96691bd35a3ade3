//! Property: any block printed canonically parses back to the same block, and its canonical
//! text is a fixed point.

use ncchannel::lang::codes::{KNOWN_G, WORD_LETTERS};
use ncchannel::lang::expr::FUNCS;
use ncchannel::lang::*;
use ncchannel::vocab::flush::FlushKind;
use proptest::prelude::*;

fn num() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-100_000i64..100_000).prop_map(|k| k as f64 / 1000.0),
        (0u32..5000).prop_map(f64::from),
        -1.0e9..1.0e9f64,
    ]
}

fn ident() -> impl Strategy<Value = String> {
    "[A-Z_][A-Z0-9_]{0,7}"
}

fn file() -> impl Strategy<Value = String> {
    "[A-Za-z0-9_][A-Za-z0-9_.-]{0,11}".prop_filter("CYCLE is the cycle keyword", |s| {
        !s.eq_ignore_ascii_case("cycle")
    })
}

fn scope() -> impl Strategy<Value = VScope> {
    prop_oneof![
        Just(VScope::Program),
        Just(VScope::Local),
        Just(VScope::SelfRetaining),
        Just(VScope::External)
    ]
}

fn var_ref(e: BoxedStrategy<Expr>) -> impl Strategy<Value = VarRef> {
    let idx = prop::collection::vec(e.clone(), 0..3);
    prop_oneof![
        (0u32..10_000, idx.clone()).prop_map(|(n, indices)| VarRef::P {
            number: Index::Const(n),
            indices
        }),
        (e, idx.clone()).prop_map(|(x, indices)| VarRef::P {
            number: Index::Expr(Box::new(x)),
            indices
        }),
        (scope(), ident(), idx).prop_map(|(scope, name, indices)| VarRef::V {
            scope,
            name,
            indices
        }),
        (0u32..100).prop_map(VarRef::CycleParam),
    ]
}

/// Variables a program only reads: `V.A.ABS.X`, `V.A.ABS[i]`, `V.G.WZ_AKT.R`, `V.G.WZ[j].R`,
/// the other tool fields and `V.G.NP[i].V…`.
fn read_only_var(e: BoxedStrategy<Expr>) -> impl Strategy<Value = VarRef> {
    prop_oneof![
        prop::sample::select(b"XYZABCUVW".to_vec()).prop_map(|l| VarRef::AxisAbs(AxisSel::Name(l))),
        e.clone()
            .prop_map(|x| VarRef::AxisAbs(AxisSel::Index(Box::new(x)))),
        Just(VarRef::ToolRadius(None)),
        e.clone()
            .prop_map(|x| VarRef::ToolRadius(Some(Box::new(x)))),
        // `V.G.WZ_AKT.L`, `V.G.WZ[j].OK`, `V.G.WZ_AKT.V.X`, `V.G.NP[i].V[j]`.
        (
            prop::option::of(e.clone()),
            prop_oneof![
                Just(ToolField::Length),
                Just(ToolField::Valid),
                prop::sample::select(b"XYZABC".to_vec())
                    .prop_map(|l| ToolField::AxisOffset(AxisSel::Name(l))),
                e.clone()
                    .prop_map(|x| ToolField::AxisOffset(AxisSel::Index(Box::new(x)))),
            ]
        )
            .prop_map(|(tool, field)| VarRef::ToolData {
                tool: tool.map(Box::new),
                field
            }),
        (e.clone(), e).prop_map(|(g, j)| VarRef::ZeroOffset {
            group: Box::new(g),
            axis: AxisSel::Index(Box::new(j))
        }),
    ]
}

fn expr() -> BoxedStrategy<Expr> {
    let leaf = prop_oneof![
        3 => num().prop_map(Expr::Num),
        1 => var_ref(num().prop_map(Expr::Num).boxed()).prop_map(|v| Expr::Var(Box::new(v))),
    ];
    leaf.prop_recursive(4, 40, 3, |inner| {
        let unop = prop_oneof![Just(UnOp::Neg), Just(UnOp::Not), Just(UnOp::Inv)];
        let binop = prop::sample::select(vec![
            BinOp::Add,
            BinOp::Sub,
            BinOp::Mul,
            BinOp::Div,
            BinOp::Pow,
            BinOp::Mod,
            BinOp::Eq,
            BinOp::Ne,
            BinOp::Lt,
            BinOp::Gt,
            BinOp::Le,
            BinOp::Ge,
            BinOp::And,
            BinOp::Or,
            BinOp::Xor,
            BinOp::BitAnd,
            BinOp::BitOr,
            BinOp::BitXor,
        ]);
        prop_oneof![
            (unop, inner.clone()).prop_map(|(o, e)| Expr::Unary(o, Box::new(e))),
            (binop, inner.clone(), inner.clone()).prop_map(|(o, a, b)| Expr::Binary(
                o,
                Box::new(a),
                Box::new(b)
            )),
            (
                prop::sample::select(FUNCS.to_vec()),
                inner.clone(),
                inner.clone()
            )
                .prop_map(|(f, a, b)| {
                    let args = if f == Func::Atan2 {
                        vec![a, b]
                    } else {
                        vec![a]
                    };
                    Expr::Func(f, args)
                }),
            var_ref(inner.clone()).prop_map(|v| Expr::Var(Box::new(v))),
            read_only_var(inner.clone()).prop_map(|v| Expr::Var(Box::new(v))),
            (
                prop::sample::select(vec![VarTest::Exist, VarTest::IsNumber, VarTest::IsString]),
                var_ref(inner)
            )
                .prop_map(|(t, v)| Expr::Test(t, Box::new(v))),
        ]
    })
    .boxed()
}

fn value() -> impl Strategy<Value = Value> {
    prop_oneof![3 => num().prop_map(Value::Num), 1 => expr().prop_map(Value::Expr)]
}

/// A letter other than G, M, H at most once per block, and an M number at most once (a second
/// one is double programming: 20765 for M).
fn once_per_letter(items: Vec<Item>) -> Vec<Item> {
    let mut seen = Vec::new();
    let mut ms = Vec::new();
    let mut m_once = |n: u32| {
        let first = !ms.contains(&n);
        ms.push(n);
        first
    };
    items
        .into_iter()
        .filter(|it| match it {
            Item::Word(w) if w.letter == b'M' => match w.value {
                Value::Num(v) => m_once(v as u32),
                Value::Expr(_) => true,
            },
            Item::FunctionValue {
                letter: b'M',
                number,
                ..
            } => m_once(*number),
            Item::Word(w) if !matches!(w.letter, b'G' | b'M' | b'H') => {
                let first = !seen.contains(&w.letter);
                seen.push(w.letter);
                first
            }
            _ => true,
        })
        .collect()
}

/// A literal moved into its word's range (`lang::range`): the parser refuses the others.
fn in_range(letter: u8, value: Value) -> Value {
    let Value::Num(v) = value else { return value };
    let v = match letter {
        b'F' | b'S' => v.abs(),
        b'T' | b'D' => v.abs().round(),
        b'I' | b'J' | b'K' | b'R' => v.clamp(-200_000.0, 200_000.0),
        _ => v,
    };
    assert!(range::word_value(letter, v).is_ok());
    Value::Num(v)
}

fn item() -> impl Strategy<Value = Item> {
    let letters: Vec<u8> = WORD_LETTERS
        .iter()
        .copied()
        .filter(|&l| l != b'G' && l != b'M' && l != b'H')
        .collect();
    // G04 must stand alone in its block: generated blocks leave it out.
    let gs: Vec<u32> = KNOWN_G.iter().copied().filter(|&g| g != 4).collect();
    prop_oneof![
        4 => (prop::sample::select(letters), value()).prop_map(|(letter, value)| Item::Word(Word { letter, value: in_range(letter, value), col: 0 })),
        1 => prop::sample::select(gs).prop_map(|g| Item::Word(Word { letter: b'G', value: Value::Num(f64::from(g)), col: 0 })),
        1 => (0u32..100).prop_map(|m| Item::Word(Word { letter: b'M', value: Value::Num(f64::from(m)), col: 0 })),
        1 => (0u32..=65_535).prop_map(|h| Item::Word(Word { letter: b'H', value: Value::Num(f64::from(h)), col: 0 })),
        1 => (var_ref(expr()), expr()).prop_map(|(target, value)| Item::assign(target, value, 0, None)),
        1 => (800u32..=819, prop::collection::vec(prop::option::of(expr()), 0..4))
            .prop_map(|(g, mut args)| {
                // The parser drops trailing gaps: they define nothing.
                while args.last().is_some_and(Option::is_none) {
                    args.pop();
                }
                Item::GCall(Box::new(ncchannel::lang::GCall { g, args, col: 0 }))
            }),
        1 => (prop::sample::select(vec![129u32, 131, 133, 134, 231, 233]), expr()).prop_map(|(g, e)| Item::GValue {
            g,
            value: match e { Expr::Num(v) => Value::Num(v), e => Value::Expr(e) },
            col: 0,
        }),
        1 => (prop::sample::select(vec![b'M', b'H']), 0u32..=65_535, expr()).prop_map(|(letter, number, e)| Item::FunctionValue {
            letter,
            number,
            value: match e { Expr::Num(v) => Value::Num(v), e => Value::Expr(e) },
            col: 0,
        }),
    ]
}

fn target() -> impl Strategy<Value = GotoTarget> {
    prop_oneof![
        (0u32..100_000).prop_map(GotoTarget::Number),
        ident().prop_map(GotoTarget::Name)
    ]
}

fn control() -> impl Strategy<Value = Control> {
    use Control::*;
    prop_oneof![
        expr().prop_map(If),
        (expr(), target()).prop_map(|(e, t)| IfGoto(e, t)),
        expr().prop_map(ElseIf),
        expr().prop_map(Switch),
        expr().prop_map(Case),
        expr().prop_map(While),
        expr().prop_map(EndDo),
        expr().prop_map(Until),
        target().prop_map(Goto),
        (var_ref(expr()), expr(), expr(), prop::option::of(expr())).prop_map(
            |(var, start, end, step)| For {
                var: Box::new(var),
                start: Box::new(start),
                end: Box::new(end),
                step: step.map(Box::new),
            }
        ),
        prop::sample::select(vec![
            Else, EndIf, Default, Break, EndSwitch, EndFor, EndWhile, Do, Repeat, Continue
        ]),
    ]
}

fn options() -> impl Strategy<Value = String> {
    prop_oneof![
        Just(String::new()),
        "[A-Z0-9_.=]([A-Z0-9_ .=,]{0,10}[A-Z0-9_.=])?"
    ]
}

fn command() -> impl Strategy<Value = Command> {
    use Command::*;
    prop_oneof![
        prop::sample::select(vec![
            Flush(FlushKind::Stop),
            Flush(FlushKind::Continue),
            Flush(FlushKind::Wait),
            CacheClearAll,
            CommentBegin,
            CommentEnd,
            Spline(SplineCommand::On),
            Spline(SplineCommand::Off),
            Spline(SplineCommand::TypeAkima),
            Spline(SplineCommand::TypeBspline),
            Var,
            EndVar,
        ]),
        file().prop_map(|file| CacheLoad { file }),
        file().prop_map(|file| CacheClear { file }),
        (any::<bool>(), options()).prop_map(|(on, options)| Hsc { on, options }),
        options().prop_map(|options| ContourMode { options }),
        (any::<bool>(), options()).prop_map(|(on, options)| ContourSwitch { on, options }),
        (
            any::<bool>(),
            "[A-Za-z0-9_ .,:]{0,20}",
            prop::collection::vec(expr(), 0..3)
        )
            .prop_map(|(save, text, args)| Msg(Box::new(ncchannel::lang::Message {
                options: if save { vec!["SAVE"] } else { Vec::new() },
                text: text + &"%d".repeat(args.len()),
                quoted: true,
                args,
            }))),
        "[A-Za-z0-9_.,:]{1,20}".prop_map(|text| Msg(Box::new(ncchannel::lang::Message {
            options: vec!["INFO", "SYN", "HMI"],
            text,
            quoted: false,
            args: Vec::new(),
        }))),
        // `#TIME` reads an expression: a literal comes back as a number, `-3` as a negation.
        expr().prop_map(|e| Time(match e {
            Expr::Num(v) => Value::Num(v.abs()),
            e => Value::Expr(e),
        })),
    ]
}

/// A cycle parameter's value: an expression or a quoted string (no `"` inside).
fn cycle_arg() -> impl Strategy<Value = CycleArg> {
    prop_oneof![
        3 => expr().prop_map(CycleArg::Expr),
        1 => "[A-Za-z0-9_ .,:-]{0,12}".prop_map(CycleArg::Str),
    ]
}

fn call() -> impl Strategy<Value = Call> {
    prop_oneof![
        file().prop_map(|file| Call::Global { file }),
        ident().prop_map(|name| Call::Local { name }),
        (
            file(),
            any::<bool>(),
            prop::collection::btree_map(0u32..20, cycle_arg(), 0..4)
        )
            .prop_map(|(name, local, params)| Call::Cycle {
                name,
                local,
                params: params.into_iter().collect(),
            }),
    ]
}

/// A program title: words after the head's name (`% 100 Drilling plate 4`).
fn title() -> impl Strategy<Value = String> {
    prop::collection::vec("[A-Za-z0-9_.-]{1,6}", 0..3).prop_map(|w| w.join(" "))
}

fn body() -> impl Strategy<Value = Body> {
    prop_oneof![
        4 => prop::collection::vec(item(), 0..6).prop_map(|items| Body::Items(once_per_letter(items))),
        2 => control().prop_map(|c| Body::Control(Box::new(c))),
        1 => command().prop_map(|c| Body::Command(Box::new(c))),
        1 => call().prop_map(|c| Body::Call(Box::new(c))),
        1 => ("[A-Za-z0-9_.-]{0,10}", title()).prop_map(|(name, title)| Body::ProgramHead(Box::new(ProgramHead { name, local: false, title }))),
        1 => (ident(), title()).prop_map(|(name, title)| Body::ProgramHead(Box::new(ProgramHead { name, local: true, title }))),
    ]
}

fn block() -> impl Strategy<Value = Block> {
    let skip = prop::option::of(1u8..=10);
    let head = prop_oneof![
        prop::option::of(0u32..100_000).prop_map(|n| (n, None)),
        (0u32..100_000).prop_map(|k| (Some(k), Some(Label::Number(k)))),
        (prop::option::of(0u32..100_000), ident()).prop_map(|(n, s)| (n, Some(Label::Name(s)))),
    ];
    (skip, head, body()).prop_map(|(skip_level, (n, label), body)| Block {
        skip_level,
        n,
        label,
        body,
    })
}

/// Columns differ between a line and its canonical text; compare blocks without them.
pub(crate) fn without_cols(mut b: Block) -> Block {
    if let Body::Items(items) = &mut b.body {
        for item in items {
            match item {
                Item::Word(w) => w.col = 0,
                Item::Assign { col, .. }
                | Item::AssignP { col, .. }
                | Item::GValue { col, .. }
                | Item::FunctionValue { col, .. } => *col = 0,
                Item::GCall(c) => c.col = 0,
                Item::NamedAxis(a) => a.col = 0,
                Item::Functions(fs) => {
                    fs.col = 0;
                    for it in &mut fs.items {
                        match it {
                            Item::Word(w) => w.col = 0,
                            Item::FunctionValue { col, .. } => *col = 0,
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn printed_block_parses_back_equal(b in block()) {
        let text = b.to_string();
        prop_assume!(text.chars().count() <= 4000);
        let parsed = parse_block(&text).map_err(|e| TestCaseError::fail(format!("{text:?}: {e}")))?;
        prop_assert_eq!(without_cols(parsed.clone()), b, "text {:?}", text);
        prop_assert_eq!(parsed.to_string(), text.clone());
        let crlf = parse_block(&format!("{text}\r\n")).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(crlf, parsed);
    }

    /// A block of words split at its blanks over lines ending in `\\` reads as the block,
    /// and every column of the joined text maps back to the line and column it came from.
    #[test]
    fn a_block_split_over_continued_lines_reads_as_the_block(
        mut b in block(),
        items in prop::collection::vec(item(), 0..8),
    ) {
        b.body = Body::Items(once_per_letter(items));
        let text = b.to_string();
        prop_assume!(text.chars().count() <= 3000);
        // The block skip, number and label stay in the first line: a block number at the
        // start of a continuation line is the line's own, not part of the block.
        let mut parts: Vec<String> = Vec::new();
        let mut in_prefix = true;
        for p in text.split(' ') {
            let b = p.as_bytes();
            in_prefix &= b.first() == Some(&b'/')
                || b.first() == Some(&b'[')
                || (b.first() == Some(&b'N') && b.get(1).is_some_and(u8::is_ascii_digit));
            match parts.last_mut() {
                Some(first) if in_prefix => {
                    first.push(' ');
                    first.push_str(p);
                }
                _ => parts.push(p.to_string()),
            }
        }
        let mut joiner = Joiner::default();
        let mut lines = Vec::new();
        for (k, part) in parts.iter().enumerate() {
            let line = if k + 1 < parts.len() { format!("{part} \\") } else { part.to_string() };
            let done = joiner.push(&line);
            prop_assert_eq!(done, k + 1 == parts.len(), "{:?}", line);
            lines.push(line);
        }
        let joined = parse_block(joiner.text()).map_err(|e| TestCaseError::fail(format!("{text:?}: {e}")))?;
        prop_assert_eq!(without_cols(joined), without_cols(parse_block(&text).unwrap()));
        for (col, c) in joiner.text().chars().enumerate() {
            let (line, at) = joiner.position(col as u32 + 1);
            let written = lines[line as usize].chars().nth(at as usize - 1);
            prop_assert!(written == Some(c) || (c == ' ' && written == Some('\\')), "{:?} col {}", joiner.text(), col + 1);
        }
    }

    #[test]
    fn arbitrary_text_never_panics(line in "\\PC{0,200}") {
        let _ = parse_block(&line);
        let _ = parse_var_declaration(&line);
        let _ = is_comment_end(&line);
    }

    #[test]
    fn nc_like_text_never_panics(line in "[NGXYZPVL$#%@\\[\\]()=+*/<>!&|^;:. 0-9.-]{0,120}") {
        if let Ok(b) = parse_block(&line) {
            // Whatever parses prints to something that parses to the same block.
            let again = parse_block(&b.to_string()).map_err(|e| TestCaseError::fail(format!("{line:?} -> {b}: {e}")))?;
            prop_assert_eq!(without_cols(again), without_cols(b));
        }
    }
}
