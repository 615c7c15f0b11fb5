//! Output files: atomic writes, VTK particle frames and their ParaView collection, CSV time
//! series and PNG plots. None of these know the solver's types beyond particle arrays.

pub(crate) mod atomic;
pub(crate) mod csv;
pub mod plots;
pub(crate) mod vtk;
