//! diagnosis.json, the output contract of discovery: the types live with the other stage contracts
//! in `crate::artifacts::diagnosis`.

pub use crate::artifacts::diagnosis::*;
