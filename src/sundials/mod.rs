//! The only FFI: SUNDIALS IDA and KLU behind safe types.
