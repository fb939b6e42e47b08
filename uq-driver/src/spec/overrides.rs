//! Settings given on the command line (`run --set KEY=VALUE`, `run --seed N`), written into a
//! study file's TOML before it is validated, so that they are checked exactly as the file's
//! own keys are and stored with the study (its text names them).
//!
//! `KEY` is a dotted path in the study file: `seed`, `method.order`, `experiment.stop`,
//! `fixed.h`. An array of tables (`[[parameters]]`, `[[qoi]]`, `[[variants]]`,
//! `[[correlation]]`) is entered by the `name` of one of its tables (`parameters.k1.std`) or
//! by its position from 0 (`correlation.0.rho`). A missing key is added (and refused by the
//! validation if the table takes no such key). `VALUE` is a TOML value (`0.1`, `3`, `true`,
//! `"lhs"`, `[1, 2]`, `{ kind = "mc", samples = 8 }`); a word that is not one is taken as a
//! string (`method.kind=lhs`).

use toml::{Table, Value};

use super::error::StudyError;

/// `text` with each `KEY=VALUE` of `sets` written in (in order: a later one wins), preceded by
/// a comment that lists them; `text` itself when `sets` is empty. Errors name the setting.
pub(crate) fn apply(text: &str, origin: &str, sets: &[String]) -> Result<String, StudyError> {
    if sets.is_empty() {
        return Ok(text.to_owned());
    }
    let invalid = |set: &str, message: String| StudyError::Invalid {
        origin: origin.to_owned(),
        at: None,
        message: format!("--set {set}: {message}"),
    };
    // A file that does not parse is reported as it is, without the settings.
    let Ok(table) = text.parse::<Table>() else {
        return Ok(text.to_owned());
    };
    let mut root = Value::Table(table);
    for set in sets {
        let (key, value) = set
            .split_once('=')
            .ok_or_else(|| invalid(set, "expected KEY=VALUE (e.g. method.order=3)".into()))?;
        let path: Vec<&str> = key.trim().split('.').map(str::trim).collect();
        if path.iter().any(|p| p.is_empty()) {
            return Err(invalid(
                set,
                format!("'{}' is not a dotted key", key.trim()),
            ));
        }
        set_in(&mut root, "", &path, parse_value(value.trim()))
            .map_err(|message| invalid(set, message))?;
    }
    let body = toml::to_string(&root).map_err(|e| invalid(&sets.join(" "), e.to_string()))?;
    let mut out = String::from("# with settings from the command line:\n");
    for set in sets {
        out.push_str(&format!("#   --set {}\n", set.replace('\n', " ")));
    }
    out.push_str(&body);
    Ok(out)
}

/// A TOML value, or the text as a string when it is not one.
fn parse_value(text: &str) -> Value {
    match format!("v = {text}").parse::<Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| Value::String(text.to_owned())),
        Err(_) => Value::String(text.to_owned()),
    }
}

/// Sets `value` at `path` below `here` (reached by the dotted key `at`), adding missing
/// tables on the way.
fn set_in(here: &mut Value, at: &str, path: &[&str], value: Value) -> Result<(), String> {
    let Some((&part, rest)) = path.split_first() else {
        *here = value;
        return Ok(());
    };
    let slot: &mut Value = match here {
        Value::Table(t) => t
            .entry(part.to_owned())
            .or_insert_with(|| Value::Table(Table::new())),
        Value::Array(items) => {
            let found = match part.parse::<usize>() {
                Ok(i) => items.get_mut(i),
                Err(_) => items
                    .iter_mut()
                    .find(|v| v.get("name").and_then(Value::as_str) == Some(part)),
            };
            found.ok_or_else(|| {
                format!(
                    "'{at}' has no entry named '{part}' (name one of its tables by its `name` \
                     or by its position from 0)"
                )
            })?
        }
        _ => return Err(format!("'{at}' is a value, not a table")),
    };
    let below = if at.is_empty() {
        part.to_owned()
    } else {
        format!("{at}.{part}")
    };
    set_in(slot, &below, rest, value)
}

#[cfg(test)]
mod tests {
    use super::*;

    const STUDY: &str = "name = \"s\"\nseed = 1\n[method]\nkind = \"scm\"\nnodes = 3\n\
                         [[parameters]]\nname = \"k1\"\nmean = 1.0\nstd = 0.1\n\
                         [[parameters]]\nname = \"k2\"\nmean = 2.0\nstd = 0.2\n";

    fn applied(sets: &[&str]) -> Result<Table, StudyError> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Ok(apply(STUDY, "s.toml", &sets)?.parse::<Table>().unwrap())
    }

    #[test]
    fn settings_reach_tables_array_entries_by_name_or_position_and_new_keys() {
        let t = applied(&[
            "seed=7",
            "method.order=2",
            "method.kind=lhs",
            "parameters.k2.std=0.5",
            "parameters.0.mean=3",
            "experiment.stop=1.5",
        ])
        .unwrap();
        assert_eq!(t["seed"].as_integer(), Some(7));
        assert_eq!(t["method"]["order"].as_integer(), Some(2));
        assert_eq!(t["method"]["kind"].as_str(), Some("lhs"));
        assert_eq!(t["parameters"][1]["std"].as_float(), Some(0.5));
        assert_eq!(t["parameters"][0]["mean"].as_integer(), Some(3));
        assert_eq!(t["parameters"][0]["std"].as_float(), Some(0.1));
        assert_eq!(t["experiment"]["stop"].as_float(), Some(1.5));
    }

    #[test]
    fn a_setting_that_names_nothing_is_refused_with_the_setting() {
        for (set, words) in [
            ("parameters.k9.std=1", "no entry named 'k9'"),
            ("seed.x=1", "'seed' is a value"),
            ("method..order=1", "not a dotted key"),
            ("seed", "expected KEY=VALUE"),
        ] {
            let e = applied(&[set]).unwrap_err().to_string();
            assert!(e.contains(words) && e.contains(set), "{set}: {e}");
        }
    }

    #[test]
    fn the_text_records_the_settings_and_is_unchanged_without_any() {
        assert_eq!(apply(STUDY, "s", &[]).unwrap(), STUDY);
        let text = apply(STUDY, "s", &["seed=9".into()]).unwrap();
        assert!(text.starts_with("# with settings from the command line:\n#   --set seed=9\n"));
    }
}
