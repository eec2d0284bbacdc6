//! Where a carried service lives on Zenoh: `dicstream/<instance>/<service>`, so that two
//! instances linked over one network never meet, as two runs on one host never do.

use wire::linked::LinkedService;

/// The key expression of `service` of `instance` (a valid instance name: letters, digits,
/// `_` and `-`, none of Zenoh's special characters).
pub fn key_expr(instance: &str, service: LinkedService) -> String {
    format!("dicstream/{instance}/{}", service.name())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_key_names_instance_and_service() {
        assert_eq!(
            key_expr("lab_a", LinkedService::RigState),
            "dicstream/lab_a/rig/state"
        );
        assert_eq!(
            key_expr("lab_a", LinkedService::Fields),
            "dicstream/lab_a/fields"
        );
    }
}
