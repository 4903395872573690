//! A GPU technique's parameters are its CPU twin's: the same table, meanings and defaults,
//! set on the twin it keeps, with errors naming the GPU technique.

use shadowlab::error::{Error, Result};
use shadowlab::techniques::{find_param, ShadowTechnique};

/// Sets parameter `key` of a GPU technique `name` on its CPU twin, whose table it shares;
/// errors name the GPU technique.
pub fn set_twin_param(
    name: &str,
    twin: &mut dyn ShadowTechnique,
    key: &str,
    value: &str,
) -> Result<()> {
    find_param(name, &twin.param_specs(), key)?;
    let cpu = twin.name();
    twin.set_param(key, value).map_err(|e| match e {
        Error::Param(m) => Error::Param(renamed(&m, cpu, name)),
        Error::Limit(m) => Error::Limit(renamed(&m, cpu, name)),
        e => e,
    })
}

/// The parameter methods of a `ShadowTechnique` impl whose parameters are its CPU twin's,
/// kept in the field `$cpu`: the twin's values and table, set through [`set_twin_param`]
/// with errors naming the GPU technique (`self.name()`).
macro_rules! twin_params {
    ($cpu:ident) => {
        fn params(&self) -> std::collections::BTreeMap<String, serde_json::Value> {
            self.$cpu.params()
        }

        fn param_specs(&self) -> Vec<shadowlab::techniques::ParamSpec> {
            self.$cpu.param_specs()
        }

        fn set_param(&mut self, key: &str, value: &str) -> shadowlab::error::Result<()> {
            let name = self.name();
            crate::twin::set_twin_param(name, &mut self.$cpu, key, value)
        }
    };
}
pub(crate) use twin_params;

/// `text` with every `cpu.` that starts a word (a parameter's `TECHNIQUE.KEY`) spelled
/// `gpu.` instead.
fn renamed(text: &str, cpu: &str, gpu: &str) -> String {
    let from = format!("{cpu}.");
    let mut out = String::with_capacity(text.len() + 8);
    let mut rest = text;
    while let Some(i) = rest.find(&from) {
        let starts_word = rest[..i]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == ':' || c == '-'));
        out.push_str(&rest[..i]);
        out.push_str(if starts_word { gpu } else { cpu });
        out.push('.');
        rest = &rest[i + from.len()..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_technique_names_are_renamed() {
        assert_eq!(
            renamed(
                "sm.resolution = 0 is outside; afsm.x and (sm.bias)",
                "sm",
                "gpu:sm"
            ),
            "gpu:sm.resolution = 0 is outside; afsm.x and (gpu:sm.bias)"
        );
    }
}
