//! The parameters held fixed by `--free` and `--fix` (family or parameter names, both
//! comma-separated): what `solve`, `batch` and `compare` fit.

use super::FixedSet;
use super::parameters::parse_param_list;

/// The held parameters for `free` and `fix`: the default set with `free`'s parameters
/// freed and `fix`'s held. A name of `free` whose parameters `fix` holds all of is
/// refused: `fix` would undo it.
pub fn held(free: Option<&str>, fix: Option<&str>) -> Result<FixedSet, String> {
    let fixed = parse_param_list(fix.unwrap_or("")).map_err(|e| format!("--fix: {e}"))?;
    for name in free.iter().flat_map(|f| f.split(',')).map(str::trim) {
        let Ok(named) = parse_param_list(name) else {
            continue;
        };
        if !named.is_empty() && named.iter().all(|p| fixed.contains(p)) {
            return Err(format!(
                "--free {name} and --fix hold the same parameters: --fix would undo \
                 --free {name}; name it in one of them"
            ));
        }
    }
    FixedSet::from_lists(free.unwrap_or(""), fix.unwrap_or(""))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Param;

    #[test]
    fn free_frees_and_fix_holds() {
        let set = held(Some("head"), Some("CamYaw")).unwrap();
        assert!(!set.is_fixed(Param::HeadYaw));
        assert!(set.is_fixed(Param::CamYaw));
        assert!(!set.is_fixed(Param::CamPitch));
        assert_eq!(held(None, None).unwrap(), FixedSet::default());
    }

    #[test]
    fn a_name_in_both_or_unknown_is_refused() {
        assert_eq!(
            held(Some("head"), Some("head")).unwrap_err(),
            "--free head and --fix hold the same parameters: --fix would undo --free head; \
             name it in one of them"
        );
        // Holding part of a freed family is what --fix is for.
        assert!(held(Some("head"), Some("HeadYaw")).is_ok());
        assert!(
            held(None, Some("Nope"))
                .unwrap_err()
                .starts_with("--fix: unknown")
        );
        assert!(
            held(Some("Nope"), None)
                .unwrap_err()
                .starts_with("--free: unknown")
        );
    }
}
