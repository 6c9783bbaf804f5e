//! "Did you mean …?" for a misspelt name: the pass names, filter names and
//! (through prism-scene) the scene's keys and names.

/// The candidate closest to `word`, if it is close enough to be what was
/// meant: at most one edit in four characters (at least one edit, case
/// ignored on both sides, so that a scene's own names such as `Glass`
/// are found too), or one of the two is a prefix of the other (`fov_deg`
/// → `fov`, `gauss` → `gaussian`).
#[must_use]
pub fn closest<'c>(word: &str, candidates: &[&'c str]) -> Option<&'c str> {
    let lower = word.to_ascii_lowercase();
    let folded: Vec<(&'c str, String)> = candidates.iter().map(|c| (*c, c.to_ascii_lowercase())).collect();
    let (best, dist) =
        folded.iter().map(|(c, l)| (*c, strsim::damerau_levenshtein(&lower, l))).min_by_key(|&(_, d)| d)?;
    let limit = (word.chars().count() / 4).max(1);
    if dist <= limit {
        return Some(best);
    }
    folded
        .iter()
        .find(|(_, l)| l.len() >= 2 && (lower.starts_with(l.as_str()) || l.starts_with(&lower)))
        .map(|(c, _)| *c)
}

/// `; did you mean `x`?` for `word` among `candidates`, or nothing.
#[must_use]
pub fn did_you_mean(word: &str, candidates: &[&str]) -> String {
    closest(word, candidates).map_or_else(String::new, |c| format!("; did you mean `{c}`?"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_words_are_suggested_and_far_ones_are_not() {
        let keys = ["center", "radius", "type", "material"];
        assert_eq!(closest("radios", &keys), Some("radius"));
        assert_eq!(closest("centre", &keys), Some("center"));
        assert_eq!(closest("Radius", &keys), Some("radius"));
        assert_eq!(closest("colour", &keys), None);
        assert_eq!(closest("fov_deg", &["fov", "up"]), Some("fov"));
        assert_eq!(closest("x", &["fov", "up"]), None);
        assert_eq!(closest("x", &[]), None);
        assert_eq!(did_you_mean("gauss", &["box", "gaussian"]), "; did you mean `gaussian`?");
        assert_eq!(did_you_mean("sinc", &["box", "gaussian"]), "");
    }

    #[test]
    fn names_with_capitals_are_matched_whatever_the_case() {
        let names = ["Glass", "RedPlastic", "floor"];
        assert_eq!(closest("glas", &names), Some("Glass"));
        assert_eq!(closest("redplastc", &names), Some("RedPlastic"));
        assert_eq!(closest("FLOOR", &names), Some("floor"));
        assert_eq!(closest("Red", &names), Some("RedPlastic"));
        assert_eq!(closest("chrome", &names), None);
    }
}
