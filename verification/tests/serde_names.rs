//! The scene names of the solid operators (the kernels' own `Deserialize` for `SolidOperator`, feature `serde`):
//! every operator reads back from its literature name (scene files) and from its variant index (the binary form
//! the driver's checkpoints use); old scene words, wrong types and bad indices are refused with a message that
//! says what is expected instead.
use lbdem_kernels::fluid::collide::SolidOperator;
use serde::de::value::{Error as ValueError, I64Deserializer, U32Deserializer};
use serde::Deserialize;

#[derive(Debug, Deserialize)]
struct Scene {
    solid_operator: SolidOperator,
}

#[test]
fn every_operator_reads_back_from_its_name_and_its_index() {
    for (i, op) in SolidOperator::ALL.into_iter().enumerate() {
        let s: Scene = toml::from_str(&format!("solid_operator = \"{}\"", op.name())).unwrap();
        assert_eq!(s.solid_operator, op);
        let by_index =
            SolidOperator::deserialize(U32Deserializer::<ValueError>::new(i as u32)).unwrap();
        assert_eq!(by_index, op);
    }
}

#[test]
fn old_words_wrong_types_and_bad_indices_say_what_is_expected() {
    let e = toml::from_str::<Scene>("solid_operator = \"bounce_back\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("non_equilibrium_bounce_back"), "{e}");
    let e = toml::from_str::<Scene>("solid_operator = \"omega\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("lambda_consistent"), "{e}");
    // A wrong type (TOML answers for itself, "wanted string or table"; a self-describing format reaches the
    // operator's own message).
    let e = SolidOperator::deserialize(I64Deserializer::<ValueError>::new(5))
        .unwrap_err()
        .to_string();
    assert!(e.contains("a solid operator name"), "{e}");
    let n = SolidOperator::ALL.len() as u32;
    let e = SolidOperator::deserialize(U32Deserializer::<ValueError>::new(n))
        .unwrap_err()
        .to_string();
    assert!(e.contains("a solid operator name"), "{e}");
}
