//! `[render] integrator`: the default, every name, and located errors.

use super::*;
use risotto_engine::integrator::GlobalIntegrator;

fn with_integrator(line: &str) -> String {
    base_with("spp = 4", &format!("spp = 4\n{line}"))
}

#[test]
fn integrator_defaults_to_the_path_tracer_and_reads_every_name() {
    assert_eq!(
        parse(BASE).unwrap().render.integrator,
        GlobalIntegrator::Path
    );
    for g in GlobalIntegrator::ALL {
        let text = with_integrator(&format!("integrator = \"{}\"", g.name()));
        assert_eq!(parse(&text).unwrap().render.integrator, g, "{}", g.name());
    }
}

#[test]
fn an_unknown_integrator_is_a_located_error_naming_the_value_and_the_choices() {
    let text = with_integrator("integrator = \"nope\"");
    let e = parse_err(&text);
    assert_message(
        &e,
        line_of(&text, "integrator = \"nope\""),
        &["integrator", "`\"nope\"`", "path", "light", "bdpt"],
    );
}

#[test]
fn an_integrator_that_is_not_a_string_is_a_located_error() {
    for value in ["3", "[\"bdpt\"]", "{ type = \"bdpt\" }"] {
        let line = format!("integrator = {value}");
        let text = with_integrator(&line);
        let e = parse_err(&text);
        assert_message(&e, line_of(&text, &line), &["integrator"]);
    }
}
