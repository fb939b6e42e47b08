//! "Did you mean …?": the closest of a list of names to a misspelt one (study names, TOML
//! keys, FMU variables), by Jaro–Winkler similarity (the `strsim` crate), and the
//! suggestions the command line adds to the messages of the TOML parser.

#![forbid(unsafe_code)]

/// The name of `candidates` closest to `wrong`, if one is close enough to be a likely typo:
/// Jaro–Winkler similarity at least 0.8, or one edit away (insertion, deletion, substitution
/// or swap of neighbours: `Kzp` for `Kpz`), or the same name in another case; `None` when
/// `wrong` is one of the candidates. One edit ranks before similarity.
pub fn closest<'a>(wrong: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let lower = wrong.to_lowercase();
    let candidates: Vec<&'a str> = candidates.into_iter().collect();
    if candidates.contains(&wrong) {
        return None;
    }
    candidates
        .into_iter()
        .map(|c| {
            let cl = c.to_lowercase();
            let jw = strsim::jaro_winkler(&lower, &cl);
            let one_edit = lower.chars().count() > 1 && strsim::osa_distance(&lower, &cl) <= 1;
            let score = if cl == lower {
                3.0
            } else if one_edit {
                1.0 + jw
            } else {
                jw
            };
            (c, score)
        })
        .filter(|(_, score)| *score >= 0.8)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(c, _)| c)
}

/// `" (did you mean `X`?)"` for a serde message naming an unknown field or variant with the
/// expected ones: ``unknown field `nodse`, expected `nodes` or `order` `` gives
/// ``did you mean `nodes`?``. `None` when the message is not of that form or nothing is close.
pub fn for_serde_message(message: &str) -> Option<String> {
    if let Some(hint) = missing_table(message) {
        return Some(hint.to_owned());
    }
    let rest = message
        .strip_prefix("unknown field `")
        .or_else(|| message.strip_prefix("unknown variant `"))
        .or_else(|| {
            message
                .find("unknown field `")
                .map(|i| &message[i + "unknown field `".len()..])
        })
        .or_else(|| {
            message
                .find("unknown variant `")
                .map(|i| &message[i + "unknown variant `".len()..])
        })?;
    let (wrong, expected) = rest.split_once('`')?;
    let names: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    closest(wrong, names.iter().copied()).map(|c| format!("did you mean `{c}`?"))
}

/// What to write for a top-level table a study file lacks.
fn missing_table(message: &str) -> Option<&'static str> {
    let field = message.split_once("missing field `")?.1.split('`').next()?;
    Some(match field {
        "experiment" => {
            "add the time grid: [experiment] with start, stop and step (s), e.g. \
             `[experiment]` `stop = 5.0` `step = 0.01` (start defaults to 0)"
        }
        "method" => "add [method] with its kind, e.g. `[method]` `kind = \"lhs\"` `samples = 100`",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_find_their_name() {
        let builtins = ["wheel-scm", "wheel-mc", "wheel-lhs-1000", "bogie-scm"];
        assert_eq!(closest("wheel-sm", builtins), Some("wheel-scm"));
        assert_eq!(closest("boogie-scm", builtins), Some("bogie-scm"));
        assert_eq!(closest("Wheel-SCM", builtins), Some("wheel-scm"));
        assert_eq!(closest("vehicle", builtins), None);
        assert_eq!(closest("wheel-scm", builtins), None, "not a typo");
        assert_eq!(closest("Kzp", ["Kpz", "Cpz", "Ksz"]), Some("Kpz"));
    }

    #[test]
    fn a_missing_experiment_or_method_table_says_what_to_write() {
        let hint = for_serde_message("missing field `experiment`").unwrap();
        assert!(
            hint.contains("[experiment]") && hint.contains("step"),
            "{hint}"
        );
        assert!(for_serde_message("missing field `method`")
            .unwrap()
            .contains("kind"));
        assert_eq!(for_serde_message("missing field `name`"), None);
    }

    #[test]
    fn serde_messages_get_a_suggestion() {
        assert_eq!(
            for_serde_message("unknown field `nodse`, expected `nodes` or `order`").as_deref(),
            Some("did you mean `nodes`?")
        );
        assert_eq!(
            for_serde_message(
                "parameter 'K': unknown variant `lognromal`, expected one of `normal`, \
                 `lognormal`, `log_normal`, `uniform`, `truncated_normal`"
            )
            .as_deref(),
            Some("did you mean `lognormal`?")
        );
        assert_eq!(
            for_serde_message("unknown field `xyz`, expected `nodes` or `order`"),
            None
        );
        assert_eq!(for_serde_message("missing field `stop`"), None);
    }
}
