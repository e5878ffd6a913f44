//! The FMI 2.0 export layer.
