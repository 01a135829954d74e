//! Reports: plots (SVG via plotters), the speed/accuracy trade-off, and the HTML/Markdown report.

pub mod chart;
pub mod docs_figures;
pub mod document;
pub mod gpu;
pub mod pareto;
pub mod pictures;
pub mod provenance;
pub mod quantize;
pub mod readme;
pub mod recommend;
pub mod stability;
pub mod sweep;
pub mod sweep_charts;
pub mod tmsm_figure;
