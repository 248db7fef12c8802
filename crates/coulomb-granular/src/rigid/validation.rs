//! Validation cases of the rigid-body simulator (issue #41): scenes with a known answer,
//! each returning the measured value next to the expected one.
