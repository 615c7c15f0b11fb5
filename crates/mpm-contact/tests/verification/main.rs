//! Verification of the contact law against exact answers: one node, analytic cases of Abe et al.
//! (2005) §5, the paper's acceleration form, corners and bad input.

#[path = "../common/mod.rs"]
mod common;

mod abe2005_single_node;
mod acceleration_form;
mod bad_input;
mod corners;
mod integrated_sliding;
