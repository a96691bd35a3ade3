//! Evaluating expressions against the decoder's parameters and variables.
//!
//! The evaluator resolves indices itself (indirect `P[P1+5]`, array `P1[2]`) and hands the
//! decoder a [`VarKey`] whose indices are plain numbers, so the decoder's storage never sees
//! an expression. Trigonometry works in degrees, as ISG does: `SIN[30]` is 0.5, `ATAN2[1, 1]`
//! is 45. Logical operators take any value with |v| ≥ 0.5 as true and give 1 or 0; bitwise
//! operators work on the values rounded to 64-bit integers (`INV 0` is -1).
//!
//! Evaluation errors carry the kernel's id where its list has one with the same meaning
//! (division by 0, square root of a negative number, logarithm <= 0), ours from 900000–999999
//! otherwise; both are in `super::codes`.

use super::block::{
    AxisSel, BinOp, Expr, Func, Index, StrFunc, ToolField, UnOp, VScope, VarRef, VarTest,
    MAX_STRING,
};

/// A variable with every index evaluated: what the decoder stores values under.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum VarKey<'e> {
    /// `P<number>` with array indices (empty for a scalar).
    P { number: u32, indices: Vec<u32> },
    /// `V.<scope>.<name>` with array indices; the name is upper-case, borrowed from the tree.
    V {
        scope: VScope,
        name: &'e str,
        indices: Vec<u32>,
    },
    /// `@P<n>`, a cycle parameter.
    CycleParam(u32),
    /// `V.A.ABS.<axis>`: the axis' absolute coordinate after the previous block.
    AxisAbs(AxisId),
    /// `V.G.WZ_AKT.R` (`None`: the active tool) or `V.G.WZ[j].R`: a tool radius.
    ToolRadius(Option<u32>),
    /// `V.G.M_FCT[n].SYNCH` (`h` false) / `V.G.H_FCT[n].SYNCH`.
    FunctionSync { h: bool, number: u32 },
    /// `V.G.WZ_AKT.<field>` (`tool` `None`) or `V.G.WZ[j].<field>`.
    ToolData {
        tool: Option<u32>,
        field: ToolFieldId,
    },
    /// `V.G.NP[group].V.<axis>`.
    ZeroOffset { group: u32, axis: AxisId },
}

/// [`crate::lang::block::ToolField`], its axis index evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ToolFieldId {
    Length,
    Valid,
    AxisOffset(AxisId),
}

/// The axis of a `V.A.` variable, its index evaluated: which axis a letter or index names
/// is the decoder's to say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AxisId {
    Letter(u8),
    Index(u32),
}

impl std::fmt::Display for VarKey<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let indices = match self {
            VarKey::P { number, indices } => {
                write!(f, "P{number}")?;
                indices
            }
            VarKey::V {
                scope,
                name,
                indices,
            } => {
                write!(f, "V.{}.{name}", scope.letter())?;
                indices
            }
            VarKey::CycleParam(n) => return write!(f, "@P{n}"),
            VarKey::AxisAbs(AxisId::Letter(l)) => return write!(f, "V.A.ABS.{}", char::from(*l)),
            VarKey::AxisAbs(AxisId::Index(i)) => return write!(f, "V.A.ABS[{i}]"),
            VarKey::ToolRadius(None) => return f.write_str("V.G.WZ_AKT.R"),
            VarKey::FunctionSync { h, number } => {
                return write!(f, "V.G.{}_FCT[{number}].SYNCH", if *h { 'H' } else { 'M' })
            }
            VarKey::ToolRadius(Some(j)) => return write!(f, "V.G.WZ[{j}].R"),
            VarKey::ToolData { tool, field } => {
                match tool {
                    None => f.write_str("V.G.WZ_AKT.")?,
                    Some(j) => write!(f, "V.G.WZ[{j}].")?,
                }
                return match field {
                    ToolFieldId::Length => f.write_str("L"),
                    ToolFieldId::Valid => f.write_str("OK"),
                    ToolFieldId::AxisOffset(a) => write!(f, "V{}", AxisSuffix(*a)),
                };
            }
            VarKey::ZeroOffset { group, axis } => {
                return write!(f, "V.G.NP[{group}].V{}", AxisSuffix(*axis))
            }
        };
        for i in indices {
            write!(f, "[{i}]")?;
        }
        Ok(())
    }
}

/// `.X` or `[i]`: an axis after a variable name.
struct AxisSuffix(AxisId);

impl std::fmt::Display for AxisSuffix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            AxisId::Letter(l) => write!(f, ".{}", char::from(l)),
            AxisId::Index(i) => write!(f, "[{i}]"),
        }
    }
}

/// The decoder's view of parameter and variable values.
pub trait Vars {
    /// The value stored under `key`, or `None` if it is not defined (or the index is outside
    /// the declared array).
    fn get(&self, key: &VarKey<'_>) -> Option<f64>;

    /// The string `key` holds (a `STRING[n]` variable, a cycle parameter `@P1="text"`), if
    /// it holds one: it exists, but has no number for [`Vars::get`] to give.
    fn get_str(&self, _key: &VarKey<'_>) -> Option<&str> {
        None
    }

    /// Whether `key` holds a string.
    fn is_string(&self, key: &VarKey<'_>) -> bool {
        self.get_str(key).is_some()
    }

    /// Why `key` has no value, when there is more to say than "undefined": a V.E. variable
    /// the list of external variables does not declare, one the program may not read, an
    /// index outside a declared V.E. array.
    fn why_missing(&self, _key: &VarKey<'_>) -> Option<EvalError> {
        None
    }
}

/// A value of an expression that may be a string: `V.L.NAME = "abc" + V.L.S`, the values of
/// `#MSG`, the operands of `==` and `!=`. Every string is at most [`MAX_STRING`] characters.
#[derive(Debug, Clone, PartialEq)]
pub enum Val {
    Num(f64),
    Str(String),
}

/// Why an expression has no value. `code()` gives the number reported to the operator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    #[error("division by zero")]
    DivisionByZero,
    #[error("square root of a negative number ({0})")]
    SqrtNegative(f64),
    #[error("{func} argument {value} outside -1..1")]
    OutOfDomain { func: &'static str, value: f64 },
    #[error("logarithm of a non-positive number ({0})")]
    LogNonPositive(f64),
    #[error("undefined variable {0}")]
    Undefined(String),
    #[error("invalid index {0}: indices and parameter numbers are whole numbers from 0")]
    BadIndex(f64),
    #[error("result is not a finite number")]
    NotFinite,
    #[error("{0} holds a string, not a number")]
    StringAsNumber(String),
    #[error("{0} is a number where a string is needed")]
    NumberAsString(String),
    #[error(
        "operator {0} not allowed for strings (only + joins two strings, == and != compare them)"
    )]
    StringOperator(&'static str),
    #[error("string of {0} characters: a string holds at most {MAX_STRING}")]
    StringTooLong(usize),
    #[error("{func}: argument {arg} is {value}, allowed {min} to {max}")]
    StringPosition {
        func: &'static str,
        arg: usize,
        value: f64,
        min: usize,
        max: usize,
    },
    /// A variable the store refuses to give, with the store's id (V.E. variables declared
    /// by a list: 20196, 20097, 21928).
    #[error("{1}")]
    Refused(u32, String),
}

impl EvalError {
    /// The error id (`super::codes`, README "Error numbers").
    pub fn code(&self) -> u32 {
        use super::codes;
        match self {
            EvalError::DivisionByZero => codes::EVAL_DIVISION_BY_ZERO,
            EvalError::SqrtNegative(_) => codes::EVAL_SQRT_NEGATIVE,
            EvalError::OutOfDomain { .. } => codes::EVAL_OUT_OF_DOMAIN,
            EvalError::LogNonPositive(_) => codes::EVAL_LOG_NON_POSITIVE,
            EvalError::Undefined(_) => codes::EVAL_UNDEFINED,
            EvalError::BadIndex(_) => codes::EVAL_BAD_INDEX,
            EvalError::NotFinite => codes::EVAL_NOT_FINITE,
            EvalError::StringAsNumber(_) => codes::EVAL_STRING_AS_NUMBER,
            EvalError::NumberAsString(_) => codes::EVAL_NUMBER_AS_STRING,
            EvalError::StringOperator(_) => codes::STRING_OPERATOR,
            EvalError::StringTooLong(_) => codes::STRING_TOO_LONG,
            EvalError::StringPosition { .. } => codes::STRING_POSITION,
            EvalError::Refused(code, _) => *code,
        }
    }
}

/// A condition is true when |v| ≥ 0.5 (TF5200 programming manual).
pub fn is_true(v: f64) -> bool {
    v.abs() >= 0.5
}

/// `$CASE` matches when the values differ by less than 0.001 (TF5200 programming manual).
pub fn case_matches(a: f64, b: f64) -> bool {
    (a - b).abs() < 0.001
}

/// Evaluate `expr` with values from `vars`.
pub fn eval(expr: &Expr, vars: &dyn Vars) -> Result<f64, EvalError> {
    let v = match expr {
        Expr::Num(v) => *v,
        Expr::Var(r) => {
            let key = resolve(r, vars)?;
            return vars.get(&key).ok_or_else(|| no_number(&key, vars));
        }
        Expr::Test(test, r) => {
            let key = resolve(r, vars)?;
            let number = vars.get(&key).is_some();
            bool_num(match test {
                VarTest::Exist => number || vars.is_string(&key),
                VarTest::IsNumber => number,
                VarTest::IsString => !number && vars.is_string(&key),
            })
        }
        Expr::Unary(op, e) => {
            let x = eval(e, vars)?;
            match op {
                UnOp::Neg => -x,
                UnOp::Not => bool_num(!is_true(x)),
                UnOp::Inv => !to_int(x)? as f64,
            }
        }
        Expr::Binary(op, a, b) if may_be_string(a) || may_be_string(b) => {
            match binary_value(*op, a, b, vars)? {
                Val::Num(v) => v,
                Val::Str(_) => return Err(EvalError::StringAsNumber(expr_text(expr))),
            }
        }
        Expr::Binary(op, a, b) => binary(*op, eval(a, vars)?, eval(b, vars)?)?,
        Expr::Str(_) => return Err(EvalError::StringAsNumber(expr_text(expr))),
        Expr::StrFunc(func, args) => match str_func(*func, args, vars)? {
            Val::Num(v) => v,
            Val::Str(_) => return Err(EvalError::StringAsNumber(expr_text(expr))),
        },
        Expr::Func(func, args) => {
            let x = match args.first() {
                Some(a) => eval(a, vars)?,
                None => return Err(EvalError::NotFinite),
            };
            match func {
                Func::Atan2 => {
                    let x2 = match args.get(1) {
                        Some(a) => eval(a, vars)?,
                        None => return Err(EvalError::NotFinite),
                    };
                    x.atan2(x2).to_degrees()
                }
                f => function(*f, x)?,
            }
        }
    };
    if v.is_finite() {
        Ok(v)
    } else {
        Err(EvalError::NotFinite)
    }
}

/// Evaluate `expr`, which may give a string.
pub fn eval_value(expr: &Expr, vars: &dyn Vars) -> Result<Val, EvalError> {
    match expr {
        Expr::Str(t) => Ok(Val::Str(t.to_string())),
        Expr::Var(r) => {
            let key = resolve(r, vars)?;
            if let Some(v) = vars.get(&key) {
                return Ok(Val::Num(v));
            }
            match vars.get_str(&key) {
                Some(t) => Ok(Val::Str(t.to_string())),
                None => Err(vars
                    .why_missing(&key)
                    .unwrap_or_else(|| EvalError::Undefined(key.to_string()))),
            }
        }
        Expr::Binary(op, a, b) => match binary_value(*op, a, b, vars)? {
            Val::Num(v) if !v.is_finite() => Err(EvalError::NotFinite),
            v => Ok(v),
        },
        Expr::StrFunc(func, args) => str_func(*func, args, vars),
        _ => eval(expr, vars).map(Val::Num),
    }
}

/// Whether `e` may give a string, judged from its form: a literal, a string function, a
/// variable that can hold one (V., @P; P parameters hold numbers), or a `+` of such.
/// Numeric expressions without any of them keep the plain numeric path.
fn may_be_string(e: &Expr) -> bool {
    match e {
        Expr::Str(_) => true,
        Expr::StrFunc(f, _) => f.gives_string(),
        Expr::Var(v) => matches!(**v, VarRef::V { .. } | VarRef::CycleParam(_)),
        Expr::Binary(BinOp::Add, a, b) => may_be_string(a) || may_be_string(b),
        _ => false,
    }
}

/// `a op b` where an operand may be a string: `+` joins two strings, `==` / `!=` compare
/// them (case-sensitive); any other operator, or a string with a number, is the kernel's
/// 21458.
fn binary_value(op: BinOp, a: &Expr, b: &Expr, vars: &dyn Vars) -> Result<Val, EvalError> {
    match (eval_value(a, vars)?, eval_value(b, vars)?) {
        (Val::Num(x), Val::Num(y)) => binary(op, x, y).map(Val::Num),
        (Val::Str(x), Val::Str(y)) => match op {
            BinOp::Add => {
                let len = x.chars().count() + y.chars().count();
                if len > MAX_STRING {
                    return Err(EvalError::StringTooLong(len));
                }
                let mut s = x;
                s.push_str(&y);
                Ok(Val::Str(s))
            }
            BinOp::Eq => Ok(Val::Num(bool_num(x == y))),
            BinOp::Ne => Ok(Val::Num(bool_num(x != y))),
            _ => Err(EvalError::StringOperator(op.symbol())),
        },
        _ => Err(EvalError::StringOperator(op.symbol())),
    }
}

/// The expression as written, for an error message (at most a line's worth).
#[cold]
fn expr_text(e: &Expr) -> String {
    let mut t = e.to_string();
    if t.len() > 80 {
        let mut end = 77;
        while !t.is_char_boundary(end) {
            end -= 1;
        }
        t.truncate(end);
        t.push_str("...");
    }
    t
}

/// The string argument `k` of `func` (a number there is 900009).
fn str_arg(func: StrFunc, args: &[Expr], k: usize, vars: &dyn Vars) -> Result<String, EvalError> {
    match args.get(k).map(|a| eval_value(a, vars)).transpose()? {
        Some(Val::Str(s)) => Ok(s),
        Some(Val::Num(_)) => Err(EvalError::NumberAsString(format!(
            "argument {} of {}",
            k + 1,
            func.name()
        ))),
        None => Err(EvalError::NotFinite),
    }
}

/// The whole-number argument `k` of `func`, within `min..=max` (else 21545).
fn pos_arg(
    func: StrFunc,
    args: &[Expr],
    k: usize,
    min: usize,
    max: usize,
    vars: &dyn Vars,
) -> Result<usize, EvalError> {
    let Some(a) = args.get(k) else {
        return Err(EvalError::NotFinite);
    };
    let v = eval(a, vars)?;
    let r = v.round();
    if (v - r).abs() > 1e-6 || r < min as f64 || r > max as f64 {
        return Err(EvalError::StringPosition {
            func: func.name(),
            arg: k + 1,
            value: v,
            min,
            max,
        });
    }
    Ok(r as usize)
}

/// The characters `from..to` (character positions, 0-based) of `s`.
fn chars_between(s: &str, from: usize, to: usize) -> String {
    s.chars().skip(from).take(to.saturating_sub(from)).collect()
}

/// A string function (TF5200 programming manual, "Operations for character strings").
/// Positions count characters from 1; a count may be 0 to the string's length, a position 1
/// to its length (outside: 21545).
fn str_func(func: StrFunc, args: &[Expr], vars: &dyn Vars) -> Result<Val, EvalError> {
    let s = str_arg(func, args, 0, vars)?;
    let len = s.chars().count();
    Ok(match func {
        StrFunc::Len => Val::Num(len as f64),
        StrFunc::Left => {
            let n = pos_arg(func, args, 1, 0, len, vars)?;
            Val::Str(chars_between(&s, 0, n))
        }
        StrFunc::Right => {
            let n = pos_arg(func, args, 1, 0, len, vars)?;
            Val::Str(chars_between(&s, len - n, len))
        }
        StrFunc::Mid => {
            let pos = pos_arg(func, args, 2, 1, len.max(1), vars)?;
            let n = pos_arg(func, args, 1, 0, len + 1 - pos, vars)?;
            Val::Str(chars_between(&s, pos - 1, pos - 1 + n))
        }
        StrFunc::Delete => {
            let pos = pos_arg(func, args, 2, 1, len.max(1), vars)?;
            let n = pos_arg(func, args, 1, 0, len + 1 - pos, vars)?;
            let mut out = chars_between(&s, 0, pos - 1);
            out.push_str(&chars_between(&s, pos - 1 + n, len));
            Val::Str(out)
        }
        StrFunc::Find => {
            let needle = str_arg(func, args, 1, vars)?;
            let at = s
                .find(needle.as_str())
                .map_or(0, |b| s[..b].chars().count() + 1);
            Val::Num(at as f64)
        }
        StrFunc::Ord => {
            let pos = if args.len() > 1 {
                pos_arg(func, args, 1, 1, len.max(1), vars)?
            } else {
                1
            };
            match s.chars().nth(pos - 1) {
                Some(c) => Val::Num(f64::from(u32::from(c))),
                None => {
                    return Err(EvalError::StringPosition {
                        func: func.name(),
                        arg: 2,
                        value: pos as f64,
                        min: 1,
                        max: len,
                    })
                }
            }
        }
    })
}

/// Evaluate the indices of `var`, so the decoder can assign to (or look up) the result.
pub fn resolve<'e>(var: &'e VarRef, vars: &dyn Vars) -> Result<VarKey<'e>, EvalError> {
    Ok(match var {
        VarRef::P { number, indices } => VarKey::P {
            number: match number {
                Index::Const(n) => *n,
                Index::Expr(e) => index(eval(e, vars)?)?,
            },
            indices: indices_of(indices, vars)?,
        },
        VarRef::V {
            scope,
            name,
            indices,
        } => VarKey::V {
            scope: *scope,
            name,
            indices: indices_of(indices, vars)?,
        },
        VarRef::CycleParam(n) => VarKey::CycleParam(*n),
        VarRef::AxisAbs(a) => VarKey::AxisAbs(axis_id(a, vars)?),
        VarRef::ToolRadius(None) => VarKey::ToolRadius(None),
        VarRef::ToolRadius(Some(e)) => VarKey::ToolRadius(Some(index(eval(e, vars)?)?)),
        VarRef::ToolData { tool, field } => VarKey::ToolData {
            tool: match tool {
                None => None,
                Some(e) => Some(index(eval(e, vars)?)?),
            },
            field: match field {
                ToolField::Length => ToolFieldId::Length,
                ToolField::Valid => ToolFieldId::Valid,
                ToolField::AxisOffset(a) => ToolFieldId::AxisOffset(axis_id(a, vars)?),
            },
        },
        VarRef::ZeroOffset { group, axis } => VarKey::ZeroOffset {
            group: index(eval(group, vars)?)?,
            axis: axis_id(axis, vars)?,
        },
        VarRef::FunctionSync { h, number } => VarKey::FunctionSync {
            h: *h,
            number: index(eval(number, vars)?)?,
        },
    })
}

/// Why `key` gave no number: it holds a string, or nothing.
#[cold]
fn no_number(key: &VarKey<'_>, vars: &dyn Vars) -> EvalError {
    if vars.is_string(key) {
        EvalError::StringAsNumber(key.to_string())
    } else {
        vars.why_missing(key)
            .unwrap_or_else(|| EvalError::Undefined(key.to_string()))
    }
}

fn indices_of(indices: &[Expr], vars: &dyn Vars) -> Result<Vec<u32>, EvalError> {
    indices.iter().map(|e| index(eval(e, vars)?)).collect()
}

/// An axis by letter or by its index evaluated.
fn axis_id(a: &AxisSel, vars: &dyn Vars) -> Result<AxisId, EvalError> {
    Ok(match a {
        AxisSel::Name(l) => AxisId::Letter(*l),
        AxisSel::Index(e) => AxisId::Index(index(eval(e, vars)?)?),
    })
}

/// An index or computed parameter number: a whole number ≥ 0 (within 1e-6, so that
/// `P[3*0.1*10]` still means P3).
fn index(v: f64) -> Result<u32, EvalError> {
    let r = v.round();
    if (v - r).abs() > 1e-6 || r < 0.0 || r > f64::from(u32::MAX) {
        return Err(EvalError::BadIndex(v));
    }
    Ok(r as u32)
}

fn bool_num(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// A value as a 64-bit integer for bitwise operators (rounded to nearest).
fn to_int(v: f64) -> Result<i64, EvalError> {
    let r = v.round();
    if r.abs() >= 9.2e18 {
        return Err(EvalError::NotFinite);
    }
    Ok(r as i64)
}

fn binary(op: BinOp, a: f64, b: f64) -> Result<f64, EvalError> {
    Ok(match op {
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Mul => a * b,
        BinOp::Div => {
            if b == 0.0 {
                return Err(EvalError::DivisionByZero);
            }
            a / b
        }
        BinOp::Mod => {
            if b == 0.0 {
                return Err(EvalError::DivisionByZero);
            }
            a % b
        }
        BinOp::Pow => a.powf(b),
        BinOp::Eq => bool_num(a == b),
        BinOp::Ne => bool_num(a != b),
        BinOp::Lt => bool_num(a < b),
        BinOp::Gt => bool_num(a > b),
        BinOp::Le => bool_num(a <= b),
        BinOp::Ge => bool_num(a >= b),
        BinOp::And => bool_num(is_true(a) && is_true(b)),
        BinOp::Or => bool_num(is_true(a) || is_true(b)),
        BinOp::Xor => bool_num(is_true(a) != is_true(b)),
        BinOp::BitAnd => (to_int(a)? & to_int(b)?) as f64,
        BinOp::BitOr => (to_int(a)? | to_int(b)?) as f64,
        BinOp::BitXor => (to_int(a)? ^ to_int(b)?) as f64,
    })
}

/// Sine and cosine of an angle in degrees, exact at multiples of 90° so that `COS[90]` is 0
/// and not 6e-17 (CNC programs compare and multiply these).
fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let r = deg % 360.0;
    if r % 90.0 == 0.0 {
        let quarter = ((r / 90.0) as i64).rem_euclid(4);
        return match quarter {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    r.to_radians().sin_cos()
}

fn function(func: Func, x: f64) -> Result<f64, EvalError> {
    Ok(match func {
        Func::Abs => x.abs(),
        Func::Sqr => x * x,
        Func::Sqrt => {
            if x < 0.0 {
                return Err(EvalError::SqrtNegative(x));
            }
            x.sqrt()
        }
        Func::Exp => x.exp(),
        Func::Ln | Func::Log => {
            if x <= 0.0 {
                return Err(EvalError::LogNonPositive(x));
            }
            if func == Func::Ln {
                x.ln()
            } else {
                x.log10()
            }
        }
        Func::Sin => sin_cos_deg(x).0,
        Func::Cos => sin_cos_deg(x).1,
        Func::Tan => {
            let (s, c) = sin_cos_deg(x);
            if c == 0.0 {
                return Err(EvalError::NotFinite);
            }
            s / c
        }
        Func::Asin | Func::Acos => {
            if !(-1.0..=1.0).contains(&x) {
                return Err(EvalError::OutOfDomain {
                    func: func.name(),
                    value: x,
                });
            }
            if func == Func::Asin {
                x.asin().to_degrees()
            } else {
                x.acos().to_degrees()
            }
        }
        Func::Atan => x.atan().to_degrees(),
        Func::Atan2 => x.atan2(1.0).to_degrees(),
        Func::Int => x.trunc(),
        Func::Fract => x.fract(),
        Func::Round => x.round(),
        Func::Floor => x.floor(),
        Func::Ceil => x.ceil(),
    })
}
