//! The `figures` stage kind: every report figure rendered to SVG, as a Collection by file name.

use super::fit_io::param_error;
use super::report::unpack;
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::options::check_groove;
use crate::report::{render_figures, FigureOptions, ReportData};

/// Renders `fig_4_2b.svg`, `fig_4_2c.svg`, … from the runs, the fits and the aggregates.
pub struct Figures;

impl StageKind for Figures {
    fn kind(&self) -> &'static str {
        "figures"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["runs", "fits"]
    }
    fn optional_inputs(&self) -> &'static [&'static str] {
        &[
            "fits_csv",
            "summary",
            "residuals",
            "comparison",
            "diagnosis",
            "under_accepted",
            "validation",
        ]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["figures"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (opts, json) = typed_params::<FigureOptions>(params)?;
        check_groove(opts.groove_angle_deg, opts.k).map_err(param_error)?;
        Ok(json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (opts, _) =
            typed_params::<FigureOptions>(input.params).map_err(|e| StageError(e.to_string()))?;
        let mut data = ReportData::from_inputs(&unpack(&input.inputs)).map_err(StageError)?;
        data.groove = opts.groove();
        let figs = render_figures(&data, &opts).map_err(StageError)?;
        let items = figs.into_iter().map(|(k, v)| (k, v.into_bytes())).collect();
        Ok(StageOutputs::from([(
            "figures".to_string(),
            Artifact::Collection(items),
        )]))
    }
}
