//! placeholder until the Embree wrapper lands
