//! Measurements shared by the kinds: health checks of a running state ([`health`]), the one steady-state
//! criterion ([`steady`]), least-squares fits ([`fit`]), flow measures ([`flow`]) and the one Darcy measurement ([`darcy`]).
pub mod darcy;
pub mod fit;
pub mod flow;
pub mod health;
pub mod steady;
