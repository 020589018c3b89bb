//! The load factors of a step (theory §11.2): one factor for every load, and optionally a factor
//! of its own for a load named by its plugin (a rigid obstacle's `F`, `Q`, …): a path that
//! presses first and then pulls back and forth (Mindlin's loop) gives the pull its own list.

use std::collections::BTreeMap;

/// The factor of each load in a step: `named` loads (by the names their plugin gives, `Q` or
/// `sphere.Q`; tractions and body forces cannot be named yet) take their own, every other load
/// `all` (theory §11.2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadFactors {
    /// The factor of every load not in `named`.
    pub all: f64,
    /// The loads with a factor of their own.
    pub named: BTreeMap<String, f64>,
}

impl LoadFactors {
    /// Every load multiplied by `factor`.
    pub fn uniform(factor: f64) -> Self {
        Self { all: factor, named: BTreeMap::new() }
    }

    /// The factor of the load `name`.
    pub fn of(&self, name: &str) -> f64 {
        self.named.get(name).copied().unwrap_or(self.all)
    }

    /// True when every load has the factor `all`.
    pub fn is_uniform(&self) -> bool {
        self.named.values().all(|&f| f == self.all)
    }

    /// These factors moved by `by` times the change from `from` to `to` (each load's own; the
    /// three share their named loads): a sub-step of a planned step (theory §11.5).
    pub fn moved(&self, by: f64, from: &Self, to: &Self) -> Self {
        let step = |k: &str, x: f64| x + by * (to.of(k) - from.of(k));
        let named = self.named.iter().map(|(k, &x)| (k.clone(), step(k, x))).collect();
        Self { all: self.all + by * (to.all - from.all), named }
    }

    /// The largest change of a factor from `from` to `to`: the increment of a planned step.
    pub fn span(from: &Self, to: &Self) -> f64 {
        let named = to.named.iter().map(|(k, &x)| (x - from.of(k)).abs());
        named.fold((to.all - from.all).abs(), f64::max)
    }

    /// The factors seen by the obstacle whose loads are named `prefix.X` (`prefix` its name) or
    /// `X` (an unnamed obstacle): its own load names without the prefix.
    pub fn of_obstacle(&self, prefix: Option<&str>) -> Self {
        let named = self
            .named
            .iter()
            .filter_map(|(k, &f)| match prefix {
                Some(p) => k.strip_prefix(p).and_then(|r| r.strip_prefix('.')).map(|r| (r.to_string(), f)),
                None => (!k.contains(['.', '['])).then(|| (k.clone(), f)),
            })
            .collect();
        Self { all: self.all, named }
    }
}

#[cfg(test)]
mod tests {
    use super::LoadFactors;

    #[test]
    fn a_named_load_takes_its_own_factor_and_the_others_follow_all() {
        let f = LoadFactors {
            all: 0.5,
            named: [("sphere.Q".to_string(), -1.0), ("Q".to_string(), 2.0), ("load[0]".to_string(), 3.0)].into(),
        };
        assert_eq!((f.of("sphere.Q"), f.of("F"), f.of("load[0]")), (-1.0, 0.5, 3.0));
        assert!(!f.is_uniform() && LoadFactors::uniform(0.3).is_uniform());
        let sphere = f.of_obstacle(Some("sphere"));
        assert_eq!((sphere.of("Q"), sphere.of("F"), sphere.named.len()), (-1.0, 0.5, 1));
        let to = LoadFactors { all: 1.0, named: [("Q".to_string(), -2.0)].into() };
        let from = LoadFactors { all: 0.0, named: [("Q".to_string(), 2.0)].into() };
        let half = from.moved(0.5, &from, &to);
        assert_eq!((half.all, half.of("Q"), LoadFactors::span(&from, &to)), (0.5, 0.0, 4.0));
        let unnamed = f.of_obstacle(None);
        assert_eq!((unnamed.of("Q"), unnamed.named.len()), (2.0, 1));
    }
}
