//! The project as a whole: README and docs against the code and artefacts, artefact and
//! module-graph hygiene, the bad-input corpus of every command, `reproduce --tiny` end to end
//! and its report in a browser.

#[path = "../common/mod.rs"]
mod common;

/// The binary's command line (not part of the library), for its argument tree: documented
/// command lines must parse with it.
#[path = "../../src/cli/mod.rs"]
#[allow(dead_code)]
mod cli;

mod artefact_hygiene;
mod bad_input;
mod docs_figures;
mod docs_hygiene;
mod module_graph;
mod readme_figures;
mod report_browser;
mod reproduce_tiny;
mod resume;
