//! Error of a technique against the PCF reference: mean |G − PCF| over all fragments of all
//! layers (Peters & Klein 2015, Section 3.2).
//!
//! OWNER: kernel/evaluate helper.
