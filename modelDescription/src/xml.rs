//! The `modelDescription.xml` writer (FMI 2.0 Co-Simulation) and the GUID, a hash of the
//! description itself so that it changes whenever the interface does.

use std::fmt::Write;
use std::sync::OnceLock;

use sha2::{Digest, Sha256};

use crate::table::{Causality, Initial, Start, VARIABLES, VarType, Variability};
use crate::{FMI_VERSION, LOG_CATEGORIES, MODEL_IDENTIFIER, UNITS};

/// Placeholder the GUID hash is computed over.
const GUID_PLACEHOLDER: &str = "{00000000-0000-0000-0000-000000000000}";

/// The GUID of this interface: a UUID-shaped SHA-256 of the description rendered with a
/// placeholder GUID (stable across builds, different for every change of the table).
pub fn guid() -> &'static str {
    // Kept inline, not on the heap: an FMU unloaded by its importer leaves no allocation.
    static GUID: OnceLock<[u8; GUID_PLACEHOLDER.len()]> = OnceLock::new();
    let bytes = GUID.get_or_init(|| {
        let h = Sha256::digest(render(GUID_PLACEHOLDER).as_bytes());
        let hex: String = h.iter().take(16).map(|b| format!("{b:02x}")).collect();
        let text = format!(
            "{{{}-{}-{}-{}-{}}}",
            &hex[0..8],
            &hex[8..12],
            &hex[12..16],
            &hex[16..20],
            &hex[20..32]
        );
        text.as_bytes()
            .try_into()
            .expect("a GUID is as long as its placeholder")
    });
    std::str::from_utf8(bytes).expect("ASCII")
}

/// The complete `modelDescription.xml`.
pub fn xml() -> String {
    render(guid())
}

/// Escapes text for an XML attribute value.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn render(guid: &str) -> String {
    let mut x = String::new();
    // Writing into a String cannot fail: the results of writeln! are ignored below.
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="{FMI_VERSION}" modelName="{MODEL_IDENTIFIER}" guid="{guid}" description="{}" generationTool="ftfusion {}" variableNamingConvention="flat" numberOfEventIndicators="0">"#,
        esc(
            "Condensation particle filter estimating the relative pose of two parts from contact wrenches and an FT-Map"
        ),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="false"/>"#
    );
    let _ = writeln!(x, "  <UnitDefinitions>");
    for (name, [kg, m, s, rad]) in UNITS {
        let mut base = String::new();
        for (attr, e) in [("kg", kg), ("m", m), ("s", s), ("rad", rad)] {
            if e != 0 {
                let _ = write!(base, r#" {attr}="{e}""#);
            }
        }
        let _ = writeln!(x, r#"    <Unit name="{name}"><BaseUnit{base}/></Unit>"#);
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    let _ = writeln!(x, "  <LogCategories>");
    for (name, description) in LOG_CATEGORIES {
        let _ = writeln!(
            x,
            r#"    <Category name="{name}" description="{}"/>"#,
            esc(description)
        );
    }
    let _ = writeln!(x, "  </LogCategories>");
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="0" stopTime="10" stepSize="0.1"/>"#
    );
    let _ = writeln!(x, "  <ModelVariables>");
    for (i, v) in VARIABLES.iter().enumerate() {
        let causality = match v.causality {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
        };
        let variability = match v.variability {
            Variability::Fixed => "fixed",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        };
        let initial = match (v.causality, v.initial) {
            (Causality::Input, _) => String::new(),
            (_, Initial::Exact) => r#" initial="exact""#.into(),
            (_, Initial::Calculated) => r#" initial="calculated""#.into(),
        };
        let _ = writeln!(
            x,
            r#"    <!-- index {} -->
    <ScalarVariable name="{}" valueReference="{}" description="{}" causality="{causality}" variability="{variability}"{initial}>"#,
            i + 1,
            v.name,
            v.vr,
            esc(v.description)
        );
        let mut attrs = String::new();
        match v.start {
            Start::None => {}
            Start::Real(r) => {
                let _ = write!(attrs, r#" start="{r:?}""#);
            }
            Start::Integer(n) => {
                let _ = write!(attrs, r#" start="{n}""#);
            }
            Start::Boolean(b) => {
                let _ = write!(attrs, r#" start="{b}""#);
            }
            Start::String(s) => {
                let _ = write!(attrs, r#" start="{}""#, esc(s));
            }
        }
        if !v.unit.is_empty() {
            let _ = write!(attrs, r#" unit="{}""#, v.unit);
        }
        for (attr, bound) in [("min", v.min), ("max", v.max)] {
            match (bound, v.ty) {
                (Some(b), VarType::Integer) => {
                    let _ = write!(attrs, r#" {attr}="{}""#, b as i64);
                }
                (Some(b), _) => {
                    let _ = write!(attrs, r#" {attr}="{b:?}""#);
                }
                (None, _) => {}
            }
        }
        let ty = match v.ty {
            VarType::Real => "Real",
            VarType::Integer => "Integer",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
        };
        let _ = writeln!(x, "      <{ty}{attrs}/>\n    </ScalarVariable>");
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let outputs: Vec<usize> = VARIABLES
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    let _ = writeln!(x, "    <Outputs>");
    for i in &outputs {
        // Outputs change only in fmi2DoStep: no direct feedthrough from the inputs.
        let _ = writeln!(x, r#"      <Unknown index="{i}" dependencies=""/>"#);
    }
    let _ = writeln!(x, "    </Outputs>");
    let _ = writeln!(x, "    <InitialUnknowns>");
    for (i, v) in VARIABLES.iter().enumerate() {
        if v.causality == Causality::Output && v.initial == Initial::Calculated {
            // Computed at initialization from the parameters (all knowns: no dependencies attribute).
            let _ = writeln!(x, r#"      <Unknown index="{}"/>"#, i + 1);
        }
    }
    let _ = writeln!(x, "    </InitialUnknowns>");
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::by_name;
    use fmi_schema::fmi2::{Fmi2ModelDescription, ScalarVariableElement};

    fn parsed() -> Fmi2ModelDescription {
        fmi_schema::deserialize(&xml()).expect("own XML parses")
    }

    #[test]
    fn guid_is_uuid_shaped_and_stable() {
        let g = guid();
        assert_eq!(g.len(), 38);
        assert!(g.starts_with('{') && g.ends_with('}'));
        assert_eq!(g.matches('-').count(), 4);
        assert_eq!(render(GUID_PLACEHOLDER).len(), xml().len());
    }

    /// The value of attribute `attr` on the type element of variable `name`, read from the text.
    fn type_attr(text: &str, name: &str, attr: &str) -> Option<f64> {
        let at = text.find(&format!(r#"<ScalarVariable name="{name}""#))?;
        let elem = &text[at..];
        let elem = &elem[elem.find("\n      <")?..];
        let elem = &elem[..elem.find("/>")?];
        let key = format!(r#" {attr}=""#);
        let v = &elem[elem.find(&key)? + key.len()..];
        v[..v.find('"')?].parse().ok()
    }

    #[test]
    fn the_parsed_xml_holds_every_variable_with_its_attributes() {
        let md = parsed();
        let text = xml();
        assert_eq!(md.fmi_version, "2.0");
        assert_eq!(md.guid, guid());
        let cs = md.co_simulation.as_ref().expect("CoSimulation element");
        assert_eq!(cs.model_identifier, MODEL_IDENTIFIER);
        assert_eq!(cs.can_get_and_set_fmu_state, Some(true));
        assert_eq!(cs.can_serialize_fmu_state, Some(true));
        let vars = &md.model_variables.variables;
        assert_eq!(vars.len(), VARIABLES.len());
        for (sv, v) in vars.iter().zip(VARIABLES) {
            assert_eq!(sv.name, v.name);
            assert_eq!(sv.value_reference, v.vr, "{}", v.name);
            assert_eq!(
                sv.causality.to_string(),
                format!("{:?}", v.causality).to_lowercase(),
                "{}",
                v.name
            );
            let variability = sv.variability.map(|x| x.to_string());
            assert_eq!(
                variability,
                Some(format!("{:?}", v.variability).to_lowercase()),
                "{}",
                v.name
            );
            assert_eq!(sv.description.as_deref(), Some(v.description));
            match (&sv.elem, v.start, v.ty) {
                (ScalarVariableElement::Real(r), Start::Real(s), VarType::Real) => {
                    assert_eq!(r.start, Some(s))
                }
                (ScalarVariableElement::Real(r), Start::None, VarType::Real) => {
                    assert_eq!(r.start, None)
                }
                (ScalarVariableElement::Integer(n), Start::Integer(s), VarType::Integer) => {
                    assert_eq!(n.start, Some(s))
                }
                (ScalarVariableElement::Integer(n), Start::None, VarType::Integer) => {
                    assert_eq!(n.start, None)
                }
                (ScalarVariableElement::Boolean(b), Start::Boolean(s), VarType::Boolean) => {
                    assert_eq!(b.start, Some(s))
                }
                (ScalarVariableElement::Boolean(b), Start::None, VarType::Boolean) => {
                    assert_eq!(b.start, None)
                }
                (ScalarVariableElement::String, Start::String(s), VarType::String) => {
                    assert!(text.contains(&format!(r#"<String start="{s}"/>"#)))
                }
                (elem, start, ty) => panic!(
                    "{}: element {elem:?} for type {ty:?}, start {start:?}",
                    v.name
                ),
            }
            // fmi-schema does not read unit, min and max: read them from the text.
            assert_eq!(type_attr(&text, v.name, "min"), v.min, "{} min", v.name);
            assert_eq!(type_attr(&text, v.name, "max"), v.max, "{} max", v.name);
            let unit = text.contains(&format!(r#"unit="{}""#, v.unit));
            assert!(v.unit.is_empty() || unit, "{} unit", v.name);
        }
    }

    #[test]
    fn model_structure_lists_every_output_once_in_index_order() {
        let md = parsed();
        let want: Vec<u32> = VARIABLES
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| i as u32 + 1)
            .collect();
        let outs: Vec<u32> = md
            .model_structure
            .outputs
            .unknowns
            .iter()
            .map(|u| u.index)
            .collect();
        assert_eq!(outs, want);
        let init: Vec<u32> = md
            .model_structure
            .initial_unknowns
            .unknowns
            .iter()
            .map(|u| u.index)
            .collect();
        assert_eq!(init, want);
        let text = xml();
        assert_eq!(text.matches(r#"dependencies="""#).count(), want.len());
        assert!(by_name("converged").is_some());
    }

    #[test]
    fn units_are_defined_for_every_unit_used() {
        let md = parsed();
        let defined: Vec<String> = md
            .unit_definitions
            .expect("UnitDefinitions")
            .units
            .into_iter()
            .map(|u| u.name)
            .collect();
        for v in VARIABLES.iter().filter(|v| !v.unit.is_empty()) {
            assert!(
                defined.iter().any(|d| d == v.unit),
                "{}: unit {}",
                v.name,
                v.unit
            );
        }
    }
}
