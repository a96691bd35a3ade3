//! Typed reads of list values: each parameter asks for the type it needs and gets an error
//! naming the parameter and pointing at the value when the text does not fit.

use super::list::{Entry, ParamList, ValueKind};
use crate::diag::Diagnostic;

/// A whole number in `0 ..= max`, written decimal or `0x…`.
pub(crate) fn uint_value(list: &ParamList, e: &Entry, max: u64) -> Result<u64, Diagnostic> {
    let name = &e.name.text;
    let v = match e.value.kind {
        ValueKind::Int(v) if v < 0 => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!("{name}: must not be negative (found {v})"),
            ))
        }
        ValueKind::Int(v) => v as u64,
        ValueKind::Hex(v) => v,
        ValueKind::Float(_) => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!("{name}: must be a whole number (found {})", e.value.text),
            ))
        }
        ValueKind::Ref(_) => return Err(unresolved(list, e)),
        ValueKind::Word | ValueKind::Quoted => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!("{name}: expected a number, found `{}`", e.value.text),
            ))
        }
    };
    if v > max {
        return Err(list.error_at(
            e,
            e.value_pos,
            format!("{name}: {v} is larger than the largest plausible value {max}"),
        ));
    }
    Ok(v)
}

/// A finite number written as an integer, `0x…` or with a fraction (the kernel's later
/// builds keep positions as REAL64), in `min ..= max`.
pub(crate) fn number_value(
    list: &ParamList,
    e: &Entry,
    min: f64,
    max: f64,
) -> Result<f64, Diagnostic> {
    let name = &e.name.text;
    let v = match e.value.kind {
        ValueKind::Int(v) => v as f64,
        ValueKind::Hex(v) => v as f64,
        ValueKind::Float(v) => v,
        ValueKind::Ref(_) => return Err(unresolved(list, e)),
        ValueKind::Word | ValueKind::Quoted => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!("{name}: expected a number, found `{}`", e.value.text),
            ))
        }
    };
    if !(min..=max).contains(&v) {
        return Err(list.error_at(
            e,
            e.value_pos,
            format!("{name}: {v} is not in the plausible range {min} … {max}"),
        ));
    }
    Ok(v)
}

/// A reference (`P-AXIS-00008.0`) the list does not resolve: the parameter it names is not
/// set in the lists read, or is not one ncchannel knows.
pub(crate) fn unresolved(list: &ParamList, e: &Entry) -> Diagnostic {
    list.error_at(
        e,
        e.value_pos,
        format!(
            "{}: refers to {}, which is not set in the lists read (or not a parameter ncchannel knows)",
            e.name.text, e.value.text
        ),
    )
}

/// A string of at most `max_chars` characters.
pub(crate) fn string_value(
    list: &ParamList,
    e: &Entry,
    max_chars: usize,
) -> Result<String, Diagnostic> {
    let s = e.value.as_str();
    let n = s.chars().count();
    if n > max_chars {
        return Err(list.error_at(
            e,
            e.value_pos,
            format!(
                "{}: {n} characters, more than the {max_chars} allowed",
                e.name.text
            ),
        ));
    }
    Ok(s.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;
    use std::path::Path;

    fn check(line: &str, max: u64) -> Result<u64, Diagnostic> {
        let (list, errs) = parse_list(Path::new("t.lis"), line);
        assert!(errs.is_empty());
        uint_value(&list, &list.entries[0], max)
    }

    #[test]
    fn uint_accepts_decimal_and_hex_and_names_the_parameter() {
        assert_eq!(check("a 12", 100).unwrap(), 12);
        assert_eq!(check("a 0x10", 100).unwrap(), 16);
        let d = check("a.b -1", 100).unwrap_err();
        assert!(
            d.message.starts_with("a.b: must not be negative"),
            "{}",
            d.message
        );
        assert_eq!(d.col, 5);
        assert!(check("a 101", 100).is_err());
        assert!(check("a 1.5", 100).is_err());
        assert!(check("a x", 100).is_err());
    }
}
