//! [`Case::validate`] for the analyses: the keys each kind reads and the
//! scene each needs.

use super::*;

impl Case {
    pub(super) fn validate_analysis(&self) -> Result<(), CaseError> {
        if let Some(AnalysisSection::Silo { slab, .. }) = &self.analysis {
            positive("analysis.slab", *slab)?;
        }
        if let Some(AnalysisSection::StaticBox { settle }) = &self.analysis {
            if !(*settle >= 0.0 && *settle < self.time.end) {
                return Err(invalid(
                    "analysis.settle",
                    settle,
                    "allowed: 0 ≤ settle < time.end",
                ));
            }
        }
        if let Some(AnalysisSection::ColumnCollapse { profile_times }) = &self.analysis {
            if profile_times.iter().any(|t| t.is_nan() || *t < 0.0) {
                return Err(invalid(
                    "analysis.profile_times",
                    format!("{profile_times:?}"),
                    "allowed: times ≥ 0 after the release [s]",
                ));
            }
        }
        if matches!(self.analysis, Some(AnalysisSection::ColumnCollapse { .. }))
            && !self.walls.iter().any(|w| w.remove_at.is_some())
        {
            return Err(invalid(
                "analysis.kind",
                "column_collapse",
                "needs walls with remove_at (the gates)",
            ));
        }
        if let Some(AnalysisSection::ErodibleBed {
            profile_times,
            probes,
            sample_interval,
            profile_interval,
            flowing_speed,
            smoothing,
        }) = &self.analysis
        {
            self.validate_erodible_bed(profile_times, probes)?;
            positive("analysis.sample_interval", *sample_interval)?;
            positive("analysis.profile_interval", *profile_interval)?;
            positive("analysis.flowing_speed", *flowing_speed)?;
            positive("analysis.smoothing", *smoothing)?;
        }
        Ok(())
    }

    /// An erodible-bed run needs one gate, a dry scene, and its profile
    /// times and probes where the run reaches.
    fn validate_erodible_bed(
        &self,
        profile_times: &[f64],
        probes: &[f64],
    ) -> Result<(), CaseError> {
        let gates = self.walls.iter().filter(|w| w.remove_at.is_some()).count();
        if gates != 1 {
            return Err(invalid(
                "analysis.kind",
                "erodible_bed",
                &format!(
                    "needs exactly one wall with remove_at (the gate that holds the column), \
                     found {gates}"
                ),
            ));
        }
        if self.fluid.is_some() {
            return Err(invalid(
                "analysis.kind",
                "erodible_bed",
                "allowed in a dry scene (no [fluid])",
            ));
        }
        if profile_times.iter().any(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(invalid(
                "analysis.profile_times",
                format!("{profile_times:?}"),
                "allowed: times ≥ 0 after the release [s]",
            ));
        }
        let (lower, upper) = (self.domain.lower[0], self.domain.upper[0]);
        if probes
            .iter()
            .any(|x| !(x.is_finite() && *x >= lower && *x <= upper))
        {
            return Err(invalid(
                "analysis.probes",
                format!("{probes:?}"),
                &format!("allowed: positions along x within the domain, [{lower}, {upper}] m"),
            ));
        }
        Ok(())
    }
}
