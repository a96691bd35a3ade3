//! Canonical NC text for a parsed block: what the parser reads back to an equal `Block`.
//!
//! Canonical means: single blanks between items, keywords and names upper-case, brackets
//! only where precedence or associativity needs them (`[P1 + 2] * 3`, `P1 - [P2 - P3]`, word
//! values and indices always in their `[ ]`), numbers in their shortest round-trip form
//! without exponent (`0.1`, `-6.789`, `3000`), `G134 50` printed as `G134=50`, `/1` as `/`.
//! Non-finite numbers (which the parser never produces) print as Rust does and do not parse.
//!
//! Minimal brackets matter beyond looks: every bracket is a nesting level the parser counts
//! against `MAX_EXPR_NESTING`, so a printer that bracketed every operation turned a long flat
//! chain the parser had accepted (`P1 >= 3 > 0 <= 0 …`) into text it refuses. The printed
//! text needs a bracket only where the parsed text had one (or a unary `+`), so it nests no
//! deeper than what was read.

use std::fmt::{self, Display, Formatter, Write};

use super::block::{
    AxisSel, BinOp, Block, Body, Call, Command, Control, CycleArg, Expr, GotoTarget, Index, Item,
    Label, ProgramHead, SplineCommand, ToolField, UnOp, VScope, Value, VarDecl, VarRef, VarType,
    Word,
};
use crate::vocab::flush::FlushKind;

impl Display for Block {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let mut sep = "";
        match self.skip_level {
            Some(1) => {
                f.write_char('/')?;
                sep = " ";
            }
            Some(k) => {
                write!(f, "/{k}")?;
                sep = " ";
            }
            None => {}
        }
        match (&self.label, self.n) {
            (Some(Label::Number(k)), _) => {
                write!(f, "{sep}N{k}:")?;
                sep = " ";
            }
            (_, Some(n)) => {
                write!(f, "{sep}N{n}")?;
                sep = " ";
            }
            _ => {}
        }
        if let Some(Label::Name(name)) = &self.label {
            write!(f, "{sep}[{name}]")?;
            sep = " ";
        }
        match &self.body {
            Body::Items(items) => {
                for item in items {
                    write!(f, "{sep}{item}")?;
                    sep = " ";
                }
                Ok(())
            }
            Body::Control(c) => write!(f, "{sep}{c}"),
            Body::Command(c) => write!(f, "{sep}{c}"),
            Body::Call(c) => write!(f, "{sep}{c}"),
            Body::ProgramHead(head) => {
                let ProgramHead { name, local, title } = &**head;
                if *local {
                    write!(f, "{sep}%L {}", FileName(name))?;
                } else if name.eq_ignore_ascii_case("L") && !title.is_empty() {
                    // `%L title` would be a local subroutine head.
                    write!(f, "{sep}%\"{name}\"")?;
                } else {
                    write!(f, "{sep}%{}", FileName(name))?;
                }
                if title.is_empty() {
                    Ok(())
                } else {
                    write!(f, " {title}")
                }
            }
        }
    }
}

impl Display for Label {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Label::Number(n) => write!(f, "N{n}:"),
            Label::Name(s) => write!(f, "[{s}]"),
        }
    }
}

impl Display for Item {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Item::Word(w) => w.fmt(f),
            Item::Assign {
                target, value, op, ..
            } => {
                let op = op.map_or("", BinOp::symbol);
                write!(f, "{target}{op}={value}")
            }
            Item::AssignP {
                number, value, op, ..
            } => {
                let op = op.map_or("", BinOp::symbol);
                write!(f, "P{number}{op}={value}")
            }
            Item::GValue { g, value, .. } => match value {
                Value::Num(v) => write!(f, "G{g}={}", Num(*v)),
                Value::Expr(e) => write!(f, "G{g}={e}"),
            },
            Item::FunctionValue {
                letter,
                number,
                value,
                ..
            } => {
                let l = char::from(*letter);
                match value {
                    Value::Num(v) => write!(f, "{l}{number}={}", Num(*v)),
                    Value::Expr(e) => write!(f, "{l}{number}={e}"),
                }
            }
            Item::NamedAxis(a) => match &a.value {
                Value::Num(v) => write!(f, "{}={}", a.name, Num(*v)),
                Value::Expr(e) => write!(f, "{}={e}", a.name),
            },
            Item::GCall(c) => {
                write!(f, "G{}", c.g)?;
                list(f, &c.args, |f, a| a.as_ref().map_or(Ok(()), |e| e.fmt(f)))
            }
            Item::Functions(fs) => {
                write!(f, "{}[", char::from(fs.owner))?;
                for (k, it) in fs.items.iter().enumerate() {
                    if k > 0 {
                        f.write_char(' ')?;
                    }
                    match it {
                        // The spindle's speed is written REV inside its brackets.
                        Item::Word(w) if w.letter == b'S' => write!(f, "REV{}", w.value)?,
                        it => it.fmt(f)?,
                    }
                }
                f.write_char(']')
            }
        }
    }
}

impl Display for Word {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_char(char::from(self.letter))?;
        self.value.fmt(f)
    }
}

/// A word's value directly after its letter: `-6.789` or `[P1 * 2]`.
impl Display for Value {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Value::Num(v) => Num(*v).fmt(f),
            Value::Expr(e) => Bracketed(e).fmt(f),
        }
    }
}

/// A number in shortest round-trip form, never with an exponent (`E` is an address letter).
struct Num(f64);

impl Display for Num {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// An expression that must be inside `[ ]` (word values, indices, `P[…]`).
struct Bracketed<'e>(&'e Expr);

impl Display for Bracketed<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(f, "[{}]", self.0)
    }
}

/// `.X` or `[…]`: an axis after a variable name (`V.G.NP[1].V.X`, `V.G.WZ_AKT.V[0]`).
struct AxisSuffix<'e>(&'e AxisSel);

impl Display for AxisSuffix<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self.0 {
            AxisSel::Name(l) => write!(f, ".{}", char::from(*l)),
            AxisSel::Index(e) => write!(f, "{}", Bracketed(e)),
        }
    }
}

/// How tightly the top of an expression binds as the parser reads it back (higher binds
/// tighter): binary levels 0 (`||`) to 8 (`* / MOD`), then unary operators, then `**`, then
/// an operand. A negative literal counts as unary: `-5 ** 2` reads as `-[5 ** 2]`.
/// `[a, b, …]`: a bracketed list as the parser reads it, each element written by `item`.
fn list<T>(
    f: &mut Formatter<'_>,
    items: impl IntoIterator<Item = T>,
    mut item: impl FnMut(&mut Formatter<'_>, T) -> fmt::Result,
) -> fmt::Result {
    f.write_char('[')?;
    for (k, x) in items.into_iter().enumerate() {
        if k > 0 {
            f.write_str(", ")?;
        }
        item(f, x)?;
    }
    f.write_char(']')
}

fn strength(e: &Expr) -> u8 {
    match e {
        Expr::Num(v) if v.is_sign_negative() => UNARY,
        Expr::Num(_)
        | Expr::Var(_)
        | Expr::Func(..)
        | Expr::Test(..)
        | Expr::Str(_)
        | Expr::StrFunc(..) => OPERAND,
        Expr::Unary(..) => UNARY,
        Expr::Binary(BinOp::Pow, ..) => POWER,
        Expr::Binary(op, ..) => op.level(),
    }
}

/// Strength of unary `-`, `NOT`, `INV` (above every binary level).
const UNARY: u8 = 9;
/// Strength of `**`: its base is an operand, its exponent a unary expression.
const POWER: u8 = 10;
/// Strength of a literal, variable, function call or bracketed expression.
const OPERAND: u8 = 11;

/// `e` where the parser expects an expression of strength `min` or tighter: bracketed when
/// it binds looser.
struct At<'e>(&'e Expr, u8);

impl Display for At<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        if strength(self.0) < self.1 {
            write!(f, "[{}]", self.0)
        } else {
            self.0.fmt(f)
        }
    }
}

impl Display for Expr {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Expr::Num(v) => Num(*v).fmt(f),
            Expr::Var(v) => v.fmt(f),
            Expr::Unary(op, e) => {
                match op {
                    UnOp::Neg => f.write_char('-')?,
                    UnOp::Not => f.write_str("NOT ")?,
                    UnOp::Inv => f.write_str("INV ")?,
                }
                match (op, e.as_ref()) {
                    // `-2` would read back as the literal -2, not as negation of 2; `- 2`
                    // reads back as the negation, and unlike `-[2]` adds no nesting level
                    // (64 negations of a literal once printed past the nesting limit).
                    (UnOp::Neg, Expr::Num(v)) if !v.is_sign_negative() => write!(f, " {e}"),
                    _ => At(e, UNARY).fmt(f),
                }
            }
            // `**` is right-associative and binds tighter than unary minus: the base is an
            // operand (`[-2] ** 2`, `[2 ** 3] ** 2`), the exponent may be unary (`2 ** -1`).
            Expr::Binary(BinOp::Pow, a, b) => {
                write!(f, "{} ** {}", At(a, OPERAND), At(b, UNARY))
            }
            // Left-associative: the left operand may be of the same level, the right one
            // must bind tighter (`P1 - [P2 - P3]`).
            Expr::Binary(op, a, b) => {
                let level = op.level();
                write!(f, "{} {} {}", At(a, level), op.symbol(), At(b, level + 1))
            }
            Expr::Func(func, args) => {
                f.write_str(func.name())?;
                list(f, args, |f, a| a.fmt(f))
            }
            Expr::Test(test, v) => write!(f, "{}[{v}]", test.name()),
            Expr::Str(t) => write!(f, "\"{t}\""),
            Expr::StrFunc(func, args) => {
                f.write_str(func.name())?;
                list(f, args, |f, a| a.fmt(f))
            }
        }
    }
}

impl BinOp {
    /// The operator as canonical NC text.
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Pow => "**",
            BinOp::Mod => "MOD",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Gt => ">",
            BinOp::Le => "<=",
            BinOp::Ge => ">=",
            BinOp::And => "&&",
            BinOp::Or => "||",
            BinOp::Xor => "XOR",
            BinOp::BitAnd => "&",
            BinOp::BitOr => "|",
            BinOp::BitXor => "^",
        }
    }
}

impl Display for VarRef {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let indices = match self {
            VarRef::P { number, indices } => {
                match number {
                    Index::Const(n) => write!(f, "P{n}")?,
                    Index::Expr(e) => write!(f, "P{}", Bracketed(e))?,
                }
                indices
            }
            VarRef::V {
                scope,
                name,
                indices,
            } => {
                write!(f, "V.{}.{name}", scope.letter())?;
                indices
            }
            VarRef::CycleParam(n) => return write!(f, "@P{n}"),
            VarRef::AxisAbs(AxisSel::Name(l)) => return write!(f, "V.A.ABS.{}", char::from(*l)),
            VarRef::AxisAbs(AxisSel::Index(e)) => return write!(f, "V.A.ABS{}", Bracketed(e)),
            VarRef::ToolRadius(None) => return f.write_str("V.G.WZ_AKT.R"),
            VarRef::ToolRadius(Some(e)) => return write!(f, "V.G.WZ{}.R", Bracketed(e)),
            VarRef::ToolData { tool, field } => {
                match tool {
                    None => f.write_str("V.G.WZ_AKT.")?,
                    Some(e) => write!(f, "V.G.WZ{}.", Bracketed(e))?,
                }
                return match field {
                    ToolField::Length => f.write_str("L"),
                    ToolField::Valid => f.write_str("OK"),
                    ToolField::AxisOffset(a) => write!(f, "V{}", AxisSuffix(a)),
                };
            }
            VarRef::ZeroOffset { group, axis } => {
                return write!(f, "V.G.NP{}.V{}", Bracketed(group), AxisSuffix(axis))
            }
            VarRef::FunctionSync { h, number } => {
                let letter = if *h { 'H' } else { 'M' };
                return write!(f, "V.G.{letter}_FCT{}.SYNCH", Bracketed(number));
            }
        };
        for e in indices {
            Bracketed(e).fmt(f)?;
        }
        Ok(())
    }
}

impl VScope {
    /// The scope letter after `V.`.
    pub fn letter(self) -> char {
        match self {
            VScope::Program => 'P',
            VScope::Local => 'L',
            VScope::SelfRetaining => 'S',
            VScope::External => 'E',
        }
    }
}

impl Display for GotoTarget {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            GotoTarget::Number(n) => write!(f, "N{n}"),
            GotoTarget::Name(s) => write!(f, "[{s}]"),
        }
    }
}

impl Display for Control {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Control::If(e) => write!(f, "$IF {e}"),
            Control::IfGoto(e, t) => write!(f, "$IF {e} $GOTO {t}"),
            Control::ElseIf(e) => write!(f, "$ELSEIF {e}"),
            Control::Else => f.write_str("$ELSE"),
            Control::EndIf => f.write_str("$ENDIF"),
            Control::Switch(e) => write!(f, "$SWITCH {e}"),
            Control::Case(e) => write!(f, "$CASE {e}"),
            Control::Default => f.write_str("$DEFAULT"),
            Control::Break => f.write_str("$BREAK"),
            Control::EndSwitch => f.write_str("$ENDSWITCH"),
            Control::For {
                var,
                start,
                end,
                step,
            } => {
                write!(f, "$FOR {var}={start}, {end}")?;
                match step {
                    Some(s) => write!(f, ", {s}"),
                    None => Ok(()),
                }
            }
            Control::EndFor => f.write_str("$ENDFOR"),
            Control::While(e) => write!(f, "$WHILE {e}"),
            Control::EndWhile => f.write_str("$ENDWHILE"),
            Control::Do => f.write_str("$DO"),
            Control::EndDo(e) => write!(f, "$ENDDO {e}"),
            Control::Repeat => f.write_str("$REPEAT"),
            Control::Until(e) => write!(f, "$UNTIL {e}"),
            Control::Continue => f.write_str("$CONTINUE"),
            Control::Goto(t) => write!(f, "$GOTO {t}"),
        }
    }
}

/// A file name as written; quoted when it holds a character that would end it.
struct FileName<'s>(&'s str);

impl Display for FileName<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let s = self.0;
        // A name with a quote inside was read unquoted (a quoted name ends at its first
        // quote), so it holds no separator and prints as it is.
        if !s.contains('"') && (s.is_empty() || s.contains([' ', '\t', ']', '(', ';'])) {
            write!(f, "\"{s}\"")
        } else {
            f.write_str(s)
        }
    }
}

impl Display for Command {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Command::Flush(FlushKind::Stop) => f.write_str("#FLUSH"),
            Command::Flush(FlushKind::Continue) => f.write_str("#FLUSH CONTINUE"),
            Command::Flush(FlushKind::Wait) => f.write_str("#FLUSH WAIT"),
            Command::CacheLoad { file } => write!(f, "#CACHE LOAD [FILE={}]", FileName(file)),
            Command::CacheClear { file } => write!(f, "#CACHE CLEAR [FILE={}]", FileName(file)),
            Command::CacheClearAll => f.write_str("#CACHE CLEAR ALL"),
            Command::CommentBegin => f.write_str("#COMMENT BEGIN"),
            Command::CommentEnd => f.write_str("#COMMENT END"),
            Command::ExplicitSync => f.write_str("#EXPL SYN"),
            Command::Spline(SplineCommand::On) => f.write_str("#SPLINE ON"),
            Command::Spline(SplineCommand::Off) => f.write_str("#SPLINE OFF"),
            Command::Spline(SplineCommand::TypeAkima) => f.write_str("#SPLINE TYPE AKIMA"),
            Command::Spline(SplineCommand::TypeBspline) => f.write_str("#SPLINE TYPE BSPLINE"),
            Command::Hsc { on, options } => {
                f.write_str(if *on { "#HSC ON" } else { "#HSC OFF" })?;
                options_fmt(f, options)
            }
            Command::ContourMode { options } => {
                f.write_str("#CONTOUR MODE")?;
                options_fmt(f, options)
            }
            Command::ContourSwitch { on, options } => {
                f.write_str(if *on {
                    "#CONTOUR MODE ON"
                } else {
                    "#CONTOUR MODE OFF"
                })?;
                options_fmt(f, options)
            }
            Command::Var => f.write_str("#VAR"),
            Command::EndVar => f.write_str("#ENDVAR"),
            Command::Msg(m) => {
                f.write_str("#MSG")?;
                for o in &m.options {
                    write!(f, " {o}")?;
                }
                if !m.quoted {
                    return write!(f, " [{}]", m.text);
                }
                write!(f, " [\"{}\"", m.text)?;
                for a in &m.args {
                    write!(f, ", {a}")?;
                }
                f.write_char(']')
            }
            Command::Time(v) => write!(f, "#TIME {v}"),
            Command::Inert { text } => write!(f, "#{text}"),
            Command::MsgFileName(v) => write!(f, "#FILENAME [MSG={v}]"),
            Command::Transform(t) => write!(f, "#{}", t.text()),
        }
    }
}

fn options_fmt(f: &mut Formatter<'_>, options: &str) -> fmt::Result {
    if options.is_empty() {
        Ok(())
    } else {
        write!(f, " [{options}]")
    }
}

impl Display for Call {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Call::Global { file } => write!(f, "L {}", FileName(file)),
            Call::Local { name } => write!(f, "LL {}", FileName(name)),
            Call::Cycle {
                name,
                local,
                params,
            } => {
                let l = if *local { "LL" } else { "L" };
                write!(f, "{l} CYCLE [NAME={}", FileName(name))?;
                for (p, a) in params {
                    match a {
                        CycleArg::Expr(e) => write!(f, " @P{p}={e}")?,
                        CycleArg::Str(s) => write!(f, " @P{p}=\"{s}\"")?,
                    }
                }
                f.write_char(']')
            }
        }
    }
}

impl Display for VarDecl {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(f, "V.{}.{}", self.scope.letter(), self.name)?;
        for d in &self.dims {
            write!(f, "[{d}]")?;
        }
        match self.ty {
            Some(VarType::String(n)) => write!(f, " : STRING[{n}]")?,
            Some(t) => write!(f, " : {}", t.name())?,
            None => {}
        }
        if let Some(e) = &self.init {
            return write!(f, "={e}");
        }
        if let Some(t) = &self.text {
            return write!(f, "=\"{t}\"");
        }
        if !self.values.is_empty() {
            f.write_char('=')?;
            list(f, &self.values, |f, e| e.fmt(f))?;
        }
        Ok(())
    }
}
