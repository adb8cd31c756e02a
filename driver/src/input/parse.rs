//! Reading scene text: the file (at most [`MAX_SCENE_BYTES`]), and its parse into a kind's scene type with
//! errors that name the full key path (`solid.bonds.strength`), the line and column, and quote the offending
//! line cut to a sensible length ([`crate::error::QUOTE_CHARS`]).
use std::io::Read;
use std::ops::Range;

use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::limits::MAX_SCENE_BYTES;
use crate::error::{cut, LbdemError, Result, QUOTE_CHARS};

/// Default hint of a scene that does not parse.
pub const SCENE_HINT: &str = "see docs/scenes.md for every key, its unit and range";

/// Read a scene file (at most [`MAX_SCENE_BYTES`]); the error names the path.
pub fn read_scene_text(path: &std::path::Path) -> Result<String> {
    let err = |e: std::io::Error| LbdemError::ReadScene {
        path: path.display().to_string(),
        source: e,
    };
    let file = std::fs::File::open(path).map_err(err)?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(err)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(err(std::io::Error::other(format!(
            "the file is larger than {} bytes; scene files hold parameters, not data",
            MAX_SCENE_BYTES
        ))));
    }
    String::from_utf8(bytes).map_err(|e| {
        err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "the file is not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        ))
    })
}

/// Parse scene text as `T` (`path` for messages). On error the message names the key path at the error.
pub fn parse_scene<T: DeserializeOwned>(text: &str, path: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| parse_error(text, path, &e, None))
}

/// The [`LbdemError::ParseScene`] of a TOML error in `text`, naming the key path at the error; `hint`
/// replaces the default hint.
pub fn parse_error(
    text: &str,
    path: &str,
    e: &toml::de::Error,
    hint: Option<String>,
) -> LbdemError {
    let raw = e.message().trim();
    let span = e.span();
    let mut key = span
        .clone()
        .and_then(|s| key_at(text, s))
        .unwrap_or_default();
    // "missing field `x`" points at the table that lacks it: name the field itself.
    if let Some(missing) = backticked(raw, "missing field `") {
        key = join(&key, &missing);
    } else if let Some(child) = child_at_fault(text, &key, raw) {
        // A table deserialized as a whole (an internally tagged enum such as `[solid.bonds]`) reports its
        // errors at the table: name the key inside it whose value or name the error quotes.
        key = join(&key, &child);
    }
    let mut message = String::new();
    if !key.is_empty() {
        message += &format!("`{}`", cut(&key, QUOTE_CHARS));
    }
    if let Some(s) = &span {
        let (line, col, source) = line_of(text, s.start);
        message += &format!(
            "{}line {line}, column {col}: {}\n    {line} | {}",
            if key.is_empty() { "" } else { " at " },
            cut(raw, 4 * QUOTE_CHARS),
            excerpt(source, col)
        );
    } else {
        message += &format!(
            "{}{}",
            if key.is_empty() { "" } else { ": " },
            cut(raw, 4 * QUOTE_CHARS)
        );
    }
    let hint = hint.unwrap_or_else(|| SCENE_HINT.to_string());
    LbdemError::ParseScene {
        path: cut(path, 4 * QUOTE_CHARS),
        key: cut(&key, QUOTE_CHARS),
        message,
        hint,
    }
}

/// The text between `prefix` and the next backtick of `message`.
pub fn backticked(message: &str, prefix: &str) -> Option<String> {
    let rest = &message[message.find(prefix)? + prefix.len()..];
    Some(rest[..rest.find('`')?].to_string())
}

fn join(parent: &str, child: &str) -> String {
    if parent.is_empty() {
        child.to_string()
    } else {
        format!("{parent}.{child}")
    }
}

/// Line (1-based), column (1-based, in characters) and the text of the line holding byte `at`.
fn line_of(text: &str, at: usize) -> (usize, usize, &str) {
    let at = at.min(text.len());
    let at = (0..=at)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let line = text[..start].matches('\n').count() + 1;
    let col = text[start..at].chars().count() + 1;
    (line, col, text[start..end].trim_end_matches('\r'))
}

/// The part of a line around column `col` (1-based), at most [`QUOTE_CHARS`] characters, with `…` where cut.
fn excerpt(line: &str, col: usize) -> String {
    let n = line.chars().count();
    if n <= QUOTE_CHARS {
        return line.to_string();
    }
    let from = col.saturating_sub(1 + QUOTE_CHARS / 2).min(n - QUOTE_CHARS);
    let piece: String = line.chars().skip(from).take(QUOTE_CHARS).collect();
    format!(
        "{}{piece}{}",
        if from > 0 { "…" } else { "" },
        if from + QUOTE_CHARS < n { "…" } else { "" }
    )
}

/// The dotted key path (`solid.bonds.strength`, `heterogeneity[1].width`) of the innermost key or value of
/// `text` whose span holds byte `span.start`; `None` if the text is not TOML or nothing holds it.
fn key_at(text: &str, span: Range<usize>) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    let mut best: Option<(usize, String)> = None;
    search_table(doc.get_ref(), "", span.start, &mut best);
    best.map(|(_, k)| k)
}

/// Record `path` in `best` if `range` holds `at` and is narrower than the best so far.
fn consider(range: Range<usize>, at: usize, path: &str, best: &mut Option<(usize, String)>) {
    if range.contains(&at) || (range.is_empty() && range.start == at) {
        let width = range.end - range.start;
        if best.as_ref().is_none_or(|(w, _)| width <= *w) {
            *best = Some((width, path.to_string()));
        }
    }
}

fn search_table(table: &DeTable<'_>, prefix: &str, at: usize, best: &mut Option<(usize, String)>) {
    for (k, v) in table.iter() {
        let path = join(prefix, k.get_ref());
        consider(k.span(), at, &path, best);
        search_value(v, &path, at, best);
    }
}

fn search_value(
    v: &Spanned<DeValue<'_>>,
    path: &str,
    at: usize,
    best: &mut Option<(usize, String)>,
) {
    consider(v.span(), at, path, best);
    match v.get_ref() {
        DeValue::Table(t) => search_table(t, path, at, best),
        DeValue::Array(a) => {
            for (i, e) in a.iter().enumerate() {
                search_value(e, &format!("{path}[{i}]"), at, best);
            }
        }
        _ => {}
    }
}

/// A value quoted by a serde error message.
enum Literal {
    Str(String),
    Bool(bool),
    Num(f64),
}

/// When the key path `key` of an error names a table, the key inside that table (relative dotted path) the
/// message `raw` is about: "unknown field `x`", or "invalid type/value: <kind> <literal>" matched against the
/// values in the table. `None` when `key` is not a table or nothing matches.
fn child_at_fault(text: &str, key: &str, raw: &str) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    if !key.is_empty() {
        for part in key.split('.') {
            let (name, index) = match part.split_once('[') {
                Some((n, i)) => (n, i.trim_end_matches(']').parse::<usize>().ok()),
                None => (part, None),
            };
            let mut v = table.get(name)?.get_ref();
            if let Some(i) = index {
                v = match v {
                    DeValue::Array(a) => a.get(i)?.get_ref(),
                    _ => return None,
                };
            }
            table = match v {
                DeValue::Table(t) => t,
                _ => return None,
            };
        }
    }
    if let Some(name) = backticked(raw, "unknown field `") {
        return table
            .iter()
            .any(|(k, _)| *k.get_ref() == name)
            .then_some(name);
    }
    let rest = raw
        .strip_prefix("invalid type: ")
        .or_else(|| raw.strip_prefix("invalid value: "))?;
    let literal = if let Some(r) = rest.strip_prefix("string \"") {
        Literal::Str(r[..r.rfind("\", expected")?].to_string())
    } else {
        let l = backticked(rest, "`")?;
        match l.parse::<bool>() {
            Ok(b) => Literal::Bool(b),
            Err(_) => Literal::Num(l.parse::<f64>().ok()?),
        }
    };
    let mut found = None;
    find_value(text, table, "", &literal, &mut found);
    found
}

/// The first key of `table` (recursively, dotted relative path) whose value is `literal`.
fn find_value(
    text: &str,
    table: &DeTable<'_>,
    prefix: &str,
    literal: &Literal,
    found: &mut Option<String>,
) {
    for (k, v) in table.iter() {
        if found.is_some() {
            return;
        }
        let path = join(prefix, k.get_ref());
        let source = text.get(v.span()).unwrap_or_default().replace('_', "");
        let hit = match (v.get_ref(), literal) {
            (DeValue::String(s), Literal::Str(l)) => s.as_ref() == l.as_str(),
            (DeValue::Boolean(b), Literal::Bool(l)) => b == l,
            (DeValue::Integer(_) | DeValue::Float(_), Literal::Num(l)) => {
                source.trim().parse::<f64>().is_ok_and(|x| x == *l)
            }
            (DeValue::Table(t), _) => {
                find_value(text, t, &path, literal, found);
                false
            }
            _ => false,
        };
        if hit {
            *found = Some(path);
        }
    }
}

/// The `[scene] kind` of a scene's TOML text as `K` (a kind enum, or `String`); `None` if the header does not
/// parse as `K` (the scene's own parser then reports the problem).
pub fn peek_kind<K: DeserializeOwned>(text: &str) -> Option<K> {
    #[derive(serde::Deserialize)]
    struct Header<K> {
        scene: KindField<K>,
    }
    #[derive(serde::Deserialize)]
    struct KindField<K> {
        kind: K,
    }
    toml::from_str::<Header<K>>(text).ok().map(|h| h.scene.kind)
}

/// What `[scene] kind` of scene text is: a string, missing, or of another type (its TOML type name).
pub enum KindField {
    /// A string.
    Name(String),
    /// No `[scene]` table or no `kind` in it.
    Missing,
    /// A `kind` that is not a string (the TOML type it is).
    WrongType(&'static str),
}

/// The `[scene] kind` of scene text that parses as TOML (`Err`: the TOML error).
pub fn kind_field(text: &str) -> std::result::Result<KindField, toml::de::Error> {
    let doc = DeTable::parse(text)?;
    let Some(scene) = doc.get_ref().get("scene") else {
        return Ok(KindField::Missing);
    };
    let DeValue::Table(t) = scene.get_ref() else {
        return Ok(KindField::Missing);
    };
    Ok(match t.get("kind").map(|v| v.get_ref()) {
        None => KindField::Missing,
        Some(DeValue::String(s)) => KindField::Name(s.to_string()),
        Some(DeValue::Integer(_)) => KindField::WrongType("an integer"),
        Some(DeValue::Float(_)) => KindField::WrongType("a float"),
        Some(DeValue::Boolean(_)) => KindField::WrongType("a boolean"),
        Some(DeValue::Datetime(_)) => KindField::WrongType("a date"),
        Some(DeValue::Array(_)) => KindField::WrongType("an array"),
        Some(DeValue::Table(_)) => KindField::WrongType("a table"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Doc {
        solid: Solid,
        #[serde(default)]
        band: Vec<Band>,
    }
    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Solid {
        friction: f64,
        bonds: Bonds,
    }
    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Bonds {
        strength: f64,
    }
    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Band {
        width: f64,
    }

    fn key_and_message(text: &str) -> (String, String) {
        match parse_scene::<Doc>(text, "t.toml").unwrap_err() {
            LbdemError::ParseScene { key, message, .. } => (key, message),
            other => panic!("{other}"),
        }
    }

    #[test]
    fn errors_name_the_full_key_path_line_and_column() {
        let (key, msg) =
            key_and_message("[solid]\nfriction = 0.5\n[solid.bonds]\nstrength = \"abc\"\n");
        assert_eq!(key, "solid.bonds.strength");
        assert!(msg.contains("line 4, column 12"), "{msg}");
        let (key, _) = key_and_message("[solid]\nfriction = 0.5\n[solid.bonds]\nstrenght = 1.0\n");
        assert_eq!(key, "solid.bonds.strenght");
        let (key, _) = key_and_message("[solid]\nfriction = 0.5\n[solid.bonds]\n");
        assert_eq!(key, "solid.bonds.strength");
        let (key, _) = key_and_message(
            "[solid]\nfriction = 0.5\n[solid.bonds]\nstrength = 1.0\n[[band]]\nwidth = 1.0\n[[band]]\nwidth = true\n",
        );
        assert_eq!(key, "band[1].width");
    }

    #[test]
    fn quoted_input_is_cut_to_a_sensible_length() {
        let long = "x".repeat(1_000_000);
        let text = format!("[solid]\nfriction = \"{long}\" junk\n");
        let e = parse_scene::<Doc>(&text, "t.toml").unwrap_err().to_string();
        assert!(e.len() < 2000, "{} characters", e.len());
        let text = format!("[solid]\nfriction = \"{long}\"\n");
        let e = parse_scene::<Doc>(&text, "t.toml").unwrap_err().to_string();
        assert!(e.len() < 2000, "{} characters", e.len());
        assert!(e.contains("solid.friction"), "{e}");
    }
}
