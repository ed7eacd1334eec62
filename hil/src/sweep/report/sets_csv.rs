//! `sets.csv`: every parameter set, ranked, one row each.

use super::Report;
use crate::sweep::spec::Spec;

impl Report {
    /// `sets.csv`: every set, ranked.
    pub fn sets_csv(&self, spec: &Spec) -> String {
        let mut head: Vec<String> = vec!["rank".into(), "set".into()];
        head.extend(spec.params.iter().map(|p| p.name.clone()));
        head.extend(
            [
                "runs",
                "successes",
                "success_rate",
                "collided",
                "close",
                "errors",
                "mean_clearance_m",
                "worst_clearance_m",
                "path_ratio",
                "time_s",
                "energy",
                "oscillation_per_100m",
                "cost",
                "score",
            ]
            .map(String::from),
        );
        let n = |x: f64, d: usize| {
            if x.is_finite() {
                format!("{x:.d$}")
            } else {
                String::new()
            }
        };
        let mut w = crate::sweep::csv::writer(Vec::new());
        // Writing to memory cannot fail.
        let _ = w.write_record(&head);
        for st in &self.ranked {
            let mut row = vec![st.rank.to_string(), st.set.to_string()];
            if let Some(values) = spec.sets.get(st.set) {
                row.extend(
                    values
                        .iter()
                        .map(|v| crate::sweep::csv::one_line(&v.plain())),
                );
            }
            row.extend([
                st.runs.to_string(),
                st.successes.to_string(),
                n(st.success_rate(), 4),
                st.collided.to_string(),
                st.close.to_string(),
                st.errors.to_string(),
                n(st.mean_clearance_m, 4),
                n(st.worst_clearance_m, 4),
                n(st.path_ratio, 4),
                n(st.time_s, 2),
                n(st.energy, 2),
                n(st.oscillation, 3),
                n(st.cost, 4),
                n(st.score, 4),
            ]);
            let _ = w.write_record(&row);
        }
        String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
    }
}
