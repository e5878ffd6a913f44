//! Parametric CAD solids of the tasks (being written).
