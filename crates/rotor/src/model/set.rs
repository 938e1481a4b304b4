//! Values of a model file set by path, before the file is validated: the `set` table of a
//! campaign run or grid and the sweep's `--set PATH=VALUE`.
//!
//! A path names one value of the file as its TOML keys joined by dots, with arrays of
//! tables indexed from 0 or selected by the element's `name` (or `id`):
//!
//! ```text
//! damping.zeta                           a key of a table
//! thermal.viscosity.nu0_mm2_s            a key of a nested table
//! thermal.bearings[1].f_v                the second [[thermal.bearings]] table
//! thermal.bearings[2#].f_v               the [[thermal.bearings]] table named "2#"
//! bearings[1#].radial_clearance_m        a mechanical bearing by its id
//! thermal.bearings[*].f_v                every [[thermal.bearings]] table
//! ```
//!
//! Every table on the path must exist; the last key may be absent (an optional key such as
//! `heat_split`), in which case the format's own check decides whether it is known. A value
//! replaces the old one keeping its comments; an integer given where the file has a float
//! is taken as that float. The edited text is then parsed and validated as the file itself
//! would be, so a bad value is reported with the field path and the reason, and it is this
//! edited text that a recording embeds (replay rebuilds exactly the model that ran).

use std::collections::BTreeMap;

use toml_edit::{DocumentMut, Item};

use super::{InvalidKind, ModelError};

/// Values to set, by path (sorted, so that the edit and its record are deterministic).
pub type ModelSet = BTreeMap<String, toml::Value>;

/// One step of a path: a key, then zero or more selections in arrays.
#[derive(Debug, PartialEq)]
struct Step<'a> {
    key: &'a str,
    select: Vec<&'a str>,
}

fn parse_path(path: &str) -> Result<Vec<Step<'_>>, String> {
    if path.trim().is_empty() {
        return Err("empty path".into());
    }
    let mut steps = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if key.is_empty() || key.contains([']', ' ', '"']) {
            return Err(format!("`{part}` is not a key (write keys joined by `.`)"));
        }
        let mut select = Vec::new();
        while !rest.is_empty() {
            let Some(close) = rest.find(']') else {
                return Err(format!("unclosed `[` in `{part}`"));
            };
            if !rest.starts_with('[') || close == 1 {
                return Err(format!("`{part}`: expected `[index]` or `[name]`"));
            }
            select.push(rest[1..close].trim().trim_matches('"'));
            rest = &rest[close + 1..];
        }
        steps.push(Step { key, select });
    }
    Ok(steps)
}

/// The keys of a table-like item, for error messages.
fn keys_of(item: &Item) -> String {
    let keys: Vec<String> = match item {
        Item::Table(t) => t.iter().map(|(k, _)| k.to_string()).collect(),
        Item::Value(toml_edit::Value::InlineTable(t)) => {
            t.iter().map(|(k, _)| k.to_string()).collect()
        }
        _ => Vec::new(),
    };
    if keys.is_empty() {
        "none".into()
    } else {
        keys.join(", ")
    }
}

/// Position in an array (of tables, or inline) chosen by `sel`: an index, or the element
/// whose `name` or `id` is `sel`.
fn position(item: &Item, sel: &str, at: &str) -> Result<usize, String> {
    let names: Vec<Option<String>> = match item {
        Item::ArrayOfTables(a) => a
            .iter()
            .map(|t| {
                t.get("name")
                    .or_else(|| t.get("id"))
                    .and_then(Item::as_str)
                    .map(str::to_string)
            })
            .collect(),
        Item::Value(toml_edit::Value::Array(a)) => a
            .iter()
            .map(|v| {
                v.as_inline_table()
                    .and_then(|t| t.get("name").or_else(|| t.get("id")))
                    .and_then(toml_edit::Value::as_str)
                    .map(str::to_string)
            })
            .collect(),
        _ => return Err(format!("`{at}` is not an array")),
    };
    if let Ok(i) = sel.parse::<usize>() {
        return if i < names.len() {
            Ok(i)
        } else {
            Err(format!(
                "`{at}` has {} entries (indices from 0), no [{i}]",
                names.len()
            ))
        };
    }
    names
        .iter()
        .position(|n| n.as_deref() == Some(sel))
        .ok_or_else(|| {
            let known: Vec<&str> = names.iter().flatten().map(String::as_str).collect();
            format!(
                "`{at}` has no entry named {sel:?} (names: {})",
                if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                }
            )
        })
}

/// The 1-based line of the value at `path` in `text` (a path as the validator's errors
/// write it, e.g. `bearings[0].initial_clearance_m`), or of the deepest key of the path
/// that exists; `None` when the text does not parse or no key of the path is found.
pub(crate) fn line_of(text: &str, path: &str) -> Option<usize> {
    use toml_edit::TableLike;
    let doc = toml_edit::Document::parse(text).ok()?;
    let steps = parse_path(path).ok()?;
    let mut table: &dyn TableLike = doc.as_table();
    let mut offset: Option<usize> = None;
    'steps: for step in &steps {
        let Some((key, item)) = table.get_key_value(step.key) else {
            break;
        };
        offset = key
            .span()
            .or_else(|| item.span())
            .map(|s| s.start)
            .or(offset);
        let mut next: Option<&dyn TableLike> = item.as_table_like();
        if let Some(sel) = step.select.first() {
            let Ok(i) = position(item, sel, step.key) else {
                break;
            };
            next = match item {
                Item::ArrayOfTables(a) => a.get(i).map(|t| {
                    offset = t
                        .iter()
                        .next()
                        .and_then(|(k, _)| t.key(k))
                        .and_then(toml_edit::Key::span)
                        .map(|s| s.start)
                        .or(offset);
                    t as &dyn TableLike
                }),
                Item::Value(toml_edit::Value::Array(a)) => a.get(i).and_then(|v| {
                    offset = v.span().map(|s| s.start).or(offset);
                    v.as_inline_table().map(|t| t as &dyn TableLike)
                }),
                _ => None,
            };
        }
        match next {
            Some(t) => table = t,
            None => break 'steps,
        }
    }
    offset.map(|o| text[..o.min(text.len())].matches('\n').count() + 1)
}

/// `value` as a `toml_edit` value, an integer turned into a float where `old` is a float.
fn edit_value(value: &toml::Value, old: Option<&Item>) -> Result<toml_edit::Value, String> {
    let value = match (value, old.and_then(Item::as_value)) {
        (toml::Value::Integer(i), Some(toml_edit::Value::Float(_))) => {
            toml::Value::Float(*i as f64)
        }
        (v, _) => v.clone(),
    };
    let text = value.to_string();
    text.parse::<toml_edit::Value>()
        .map_err(|e| format!("value {text} cannot be written back as TOML: {e}"))
}

fn set_one(doc: &mut DocumentMut, path: &str, value: &toml::Value) -> Result<(), String> {
    let steps = parse_path(path)?;
    let Some((last, inner)) = steps.split_last() else {
        return Err("empty path".into());
    };
    let mut item: &mut Item = doc.as_item_mut();
    let mut at = String::new();
    for step in inner.iter().chain(std::iter::once(last)) {
        let is_last = std::ptr::eq(step, last);
        let parent_keys = keys_of(item);
        let here = if at.is_empty() {
            step.key.to_string()
        } else {
            format!("{at}.{}", step.key)
        };
        if is_last && step.select.is_empty() {
            let table_like = matches!(
                item,
                Item::Table(_) | Item::Value(toml_edit::Value::InlineTable(_))
            );
            if !table_like {
                return Err(format!("`{at}` is not a table"));
            }
            let old = item.get(step.key);
            if matches!(old, Some(Item::Table(_) | Item::ArrayOfTables(_))) {
                return Err(format!(
                    "`{here}` is a table; set one of its keys ({})",
                    old.map(keys_of).unwrap_or_default()
                ));
            }
            let mut new = edit_value(value, old)?;
            if let Some(old) = old.and_then(Item::as_value) {
                *new.decor_mut() = old.decor().clone();
            }
            match item {
                Item::Table(t) => {
                    t.insert(step.key, Item::Value(new));
                }
                Item::Value(toml_edit::Value::InlineTable(t)) => {
                    t.insert(step.key, new);
                }
                _ => return Err(format!("`{at}` is not a table")),
            }
            return Ok(());
        }
        // (`get_mut` of `toml_edit` inserts an empty item for an absent key: ask first)
        let present = item.get(step.key).is_some_and(|i| !i.is_none());
        item = match item.get_mut(step.key).filter(|_| present) {
            Some(next) => next,
            None if at.is_empty() => {
                return Err(format!(
                    "the file has no table `{here}` (top-level keys: {parent_keys})"
                ));
            }
            None => {
                return Err(format!(
                    "`{at}` has no key `{}` (keys: {parent_keys})",
                    step.key
                ));
            }
        };
        at = here;
        for sel in &step.select {
            let i = position(item, sel, &at)?;
            at = format!("{at}[{sel}]");
            item = match item.get_mut(i) {
                Some(next) => next,
                None => return Err(format!("`{at}` cannot be selected")),
            };
        }
        if is_last {
            return Err(format!(
                "`{at}` is an entry of an array; set one of its keys ({})",
                keys_of(item)
            ));
        }
    }
    Ok(())
}

/// Applies `set` to the model text `text` (file `file`, for errors) and returns the
/// edited text; unchanged when `set` is empty. The error names the path and the reason.
/// The result still has to be validated ([`super::Model::from_str`]).
pub fn apply(text: &str, file: &str, set: &ModelSet) -> Result<String, ModelError> {
    if set.is_empty() {
        return Ok(text.to_string());
    }
    let invalid = |path: &str, reason: String| ModelError::Invalid {
        file: file.to_string(),
        line: None,
        path: format!("set {path}"),
        kind: InvalidKind::Conflict(reason),
    };
    let mut doc: DocumentMut = text
        .parse()
        .map_err(|e: toml_edit::TomlError| invalid("(file)", e.message().to_string()))?;
    for (path, value) in set {
        for one in expand(&doc, path).map_err(|reason| invalid(path, reason))? {
            set_one(&mut doc, &one, value).map_err(|reason| invalid(path, reason))?;
        }
    }
    Ok(doc.to_string())
}

/// The item at `path` (keys and selections, no `[*]`), for reading.
fn item_at<'a>(doc: &'a DocumentMut, path: &str) -> Result<&'a Item, String> {
    let mut item: &Item = doc.as_item();
    let mut at = String::new();
    for step in parse_path(path)? {
        let here = if at.is_empty() {
            step.key.to_string()
        } else {
            format!("{at}.{}", step.key)
        };
        item = match item.get(step.key).filter(|i| !i.is_none()) {
            Some(next) => next,
            None if at.is_empty() => return Err(format!("the file has no table `{here}`")),
            None => return Err(format!("`{at}` has no key `{}`", step.key)),
        };
        at = here;
        for sel in &step.select {
            let i = position(item, sel, &at)?;
            at = format!("{at}[{sel}]");
            item = item
                .get(i)
                .ok_or_else(|| format!("`{at}` cannot be selected"))?;
        }
    }
    Ok(item)
}

/// `path` with every `[*]` replaced by each index of its array in turn (the paths of every
/// entry); `path` itself when it has none. An array without entries is an error (the set
/// would change nothing).
fn expand(doc: &DocumentMut, path: &str) -> Result<Vec<String>, String> {
    let Some((head, tail)) = path.split_once("[*]") else {
        return Ok(vec![path.to_string()]);
    };
    let n = match item_at(doc, head)? {
        Item::ArrayOfTables(a) => a.len(),
        Item::Value(toml_edit::Value::Array(a)) => a.len(),
        _ => {
            return Err(format!(
                "`{head}` is not an array (`[*]` selects every entry)"
            ));
        }
    };
    if n == 0 {
        return Err(format!("`{head}` has no entries"));
    }
    let mut out = Vec::new();
    for i in 0..n {
        out.extend(expand(doc, &format!("{head}[{i}]{tail}"))?);
    }
    Ok(out)
}

/// Parses `PATH=VALUE` (the command line's `--set`): the value is TOML (`3.0`, `"ball"`,
/// `[1, 2]`), or, when it does not parse as TOML, the bare text as a string.
pub fn parse_assignment(text: &str) -> Result<(String, toml::Value), String> {
    let Some((path, value)) = text.split_once('=') else {
        return Err(format!("`{text}`: expected PATH=VALUE"));
    };
    let path = path.trim();
    parse_path(path).map_err(|e| format!("`{text}`: {e}"))?;
    let value = value.trim();
    let parsed = format!("v = {value}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_string()));
    Ok((path.to_string(), parsed))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "\
name = \"m\"
[damping]
zeta = 0.02 # the default
[[bearings]]
id = \"1#\"
k = 1.0
[[bearings]]
id = \"2#\"
k = 2.0
";

    fn one(path: &str, value: toml::Value) -> Result<String, String> {
        let set = ModelSet::from([(path.to_string(), value)]);
        apply(TEXT, "m.toml", &set).map_err(|e| e.to_string())
    }

    #[test]
    fn sets_by_key_index_and_name_keeping_comments() {
        let out = one("damping.zeta", toml::Value::Float(0.05)).expect("ok");
        assert!(out.contains("zeta = 0.05 # the default"), "{out}");
        let out = one("bearings[1].k", toml::Value::Integer(7)).expect("ok");
        let t: toml::Table = out.parse().expect("ok");
        assert_eq!(t["bearings"][1]["k"].as_float(), Some(7.0));
        let out = one("bearings[1#].k", toml::Value::Float(9.0)).expect("ok");
        let t: toml::Table = out.parse().expect("ok");
        assert_eq!(t["bearings"][0]["k"].as_float(), Some(9.0));
        assert_eq!(t["bearings"][1]["k"].as_float(), Some(2.0));
        // an absent last key is added (the format's check decides whether it is known)
        let out = one("damping.extra", toml::Value::Boolean(true)).expect("ok");
        assert!(out.contains("extra = true"));
    }

    #[test]
    fn bad_paths_name_the_path_and_reason() {
        let e = one("dampin.zeta", toml::Value::Float(1.0)).expect_err("an error");
        assert!(
            e.contains("set dampin.zeta") && e.contains("no table `dampin`"),
            "{e}"
        );
        let e = one("bearings[5].k", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("2 entries"), "{e}");
        let e = one("bearings[9#].k", toml::Value::Float(1.0)).expect_err("an error");
        assert!(
            e.contains("no entry named \"9#\"") && e.contains("1#, 2#"),
            "{e}"
        );
        let e = one("damping", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("is a table"), "{e}");
        let e = one("bearings[0]", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("entry of an array"), "{e}");
        let e = one("name.x", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("is not a table"), "{e}");
        let e = one("bearings[0.k", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("unclosed"), "{e}");
    }

    #[test]
    fn a_star_sets_every_entry_of_an_array() {
        let out = one("bearings[*].k", toml::Value::Float(5.0)).expect("ok");
        let t: toml::Table = out.parse().expect("ok");
        assert_eq!(t["bearings"][0]["k"].as_float(), Some(5.0));
        assert_eq!(t["bearings"][1]["k"].as_float(), Some(5.0));
        assert_eq!(t["damping"]["zeta"].as_float(), Some(0.02));
        let e = one("damping[*].zeta", toml::Value::Float(1.0)).expect_err("an error");
        assert!(
            e.contains("set damping[*].zeta") && e.contains("`damping` is not an array"),
            "{e}"
        );
        let e = one("shafts[*].k", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("no table `shafts`"), "{e}");
        let e = one("bearings[*].k.x", toml::Value::Float(1.0)).expect_err("an error");
        assert!(e.contains("set bearings[*].k.x"), "{e}");
    }

    #[test]
    fn lines_of_paths() {
        let text = "a = 1\n\n[damping]\nzeta = 0.03\n\n[[bearings]]\nid = \"1#\"\nk = 2\n\n[[bearings]]\nid = \"2#\"\nk = 3\n";
        assert_eq!(line_of(text, "a"), Some(1));
        assert_eq!(line_of(text, "damping.zeta"), Some(4));
        assert_eq!(line_of(text, "bearings[1].k"), Some(12));
        assert_eq!(line_of(text, "bearings[1#].k"), Some(8));
        // the deepest key that exists
        assert_eq!(line_of(text, "damping.missing"), Some(3));
        assert_eq!(line_of(text, "nothing.here"), None);
    }

    #[test]
    fn assignments_parse_toml_values() {
        assert_eq!(
            parse_assignment("damping.zeta=0.05").expect("ok"),
            ("damping.zeta".into(), toml::Value::Float(0.05))
        );
        assert_eq!(
            parse_assignment("a.b = -3").expect("ok").1,
            toml::Value::Integer(-3)
        );
        assert_eq!(
            parse_assignment("a.kind=ball").expect("ok").1,
            toml::Value::String("ball".into())
        );
        assert!(parse_assignment("no-equals").is_err());
    }
}
