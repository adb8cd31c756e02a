//! Scene input below every kind: reading and parsing scene text with errors that name the full key path
//! ([`parse`]), and the limits every size a scene implies is checked against before anything is allocated
//! ([`limits`]). It depends on `error` only, so that `run` (which parses and validates a scene in
//! `run::Case::read`), `scene` and every kind share one code path for `lbdem check` and `lbdem run`.
pub mod limits;
pub mod parse;
