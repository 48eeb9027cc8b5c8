//! Access control by certificate identity: Zenoh's access control, default deny, with one
//! policy that lets the `--allow`ed identities (certificate common names) do only what their
//! side of the relay needs, on the scene's keys only.
//!
//! | role | the allowed peer may send in | the relay may send out to it |
//! |---|---|---|
//! | exporter (serves readers) | subscriptions, snapshot queries, liveliness interest | segments and manifests, query replies, its queryable, the liveliness token |
//! | importer (trusts one exporter) | segments and manifests, query replies, its queryable, the liveliness token | subscriptions, snapshot queries, liveliness interest |
//!
//! Any other peer, even with a certificate of the same CA, matches no subject: every
//! message to or from it is dropped, so it can neither put on an importer's key nor read
//! an exporter's scene.

use crate::keys::SceneKeys;

/// Which end of the relay a session is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Serves the scene to the allowed identities.
    Export,
    /// Takes the scene from the allowed identities.
    Import,
}

/// What the side that serves a scene sends: data, replies and the declarations that
/// advertise it.
const SERVING: &str = r#"["put", "reply", "declare_queryable", "liveliness_token"]"#;

/// What the side that takes a scene sends: the declarations and queries that ask for it.
const ASKING: &str =
    r#"["declare_subscriber", "query", "declare_liveliness_subscriber", "liveliness_query"]"#;

/// Zenoh's `access_control` setting (JSON5) for `role` on `keys`, allowing `identities`.
pub fn access_control(role: Role, keys: &SceneKeys, identities: &[String]) -> String {
    let (ingress, egress) = match role {
        Role::Export => (ASKING, SERVING),
        Role::Import => (SERVING, ASKING),
    };
    let key = format!("{:?}", keys.all());
    let names: Vec<String> = identities.iter().map(|n| format!("{n:?}")).collect();
    format!(
        r#"{{
  enabled: true,
  default_permission: "deny",
  rules: [
    {{ id: "in", messages: {ingress}, flows: ["ingress"], permission: "allow", key_exprs: [{key}] }},
    {{ id: "out", messages: {egress}, flows: ["egress"], permission: "allow", key_exprs: [{key}] }},
  ],
  subjects: [{{ id: "allowed", cert_common_names: [{names}] }}],
  policies: [{{ id: "relay", rules: ["in", "out"], subjects: ["allowed"] }}],
}}"#,
        names = names.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zenoh_takes_the_setting_for_both_roles() {
        let keys = SceneKeys::new("robots/r1/office").expect("key");
        for role in [Role::Export, Role::Import] {
            let setting = access_control(role, &keys, &["base".into(), "laptop".into()]);
            let mut config = zenoh::Config::default();
            config
                .insert_json5("access_control", &setting)
                .unwrap_or_else(|e| panic!("{role:?}: {e}\n{setting}"));
            let stored = config.get_json("access_control").expect("key");
            assert!(stored.contains("\"deny\""), "{stored}");
            assert!(stored.contains("\"laptop\""), "{stored}");
            assert!(stored.contains("robots/r1/office/**"), "{stored}");
        }
    }
}
