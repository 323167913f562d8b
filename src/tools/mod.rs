//! Tools that measure the renderer rather than render: backend agreement ([`agree`]), the stress
//! suite ([`stress`]), error against time ([`converge`], drawn by [`plot`]), speed ([`bench`](mod@bench)),
//! and the lecture's Monte Carlo examples ([`montecarlo`]). They sit above the integrators and
//! nothing in the renderer imports them.

pub mod agree;
pub mod bench;
pub mod converge;
pub mod info;
pub mod montecarlo;
pub mod plot;
pub mod stress;
