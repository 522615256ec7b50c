//! Every model under `examples/` checks clean.

#[test]
fn every_example_checks_clean() {
    let dir = crate::root().join("examples");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).expect("examples/ exists") {
        let path = entry.expect("examples/ is readable").path();
        if path.extension().is_some_and(|e| e == "lag") {
            let bytes = std::fs::read(&path).expect("example is readable");
            let name = path.display().to_string();
            if let Err(rendered) = crate::check_bytes(&bytes, &name) {
                panic!("{name} has errors:\n{rendered}");
            }
            checked += 1;
        }
    }
    assert!(checked >= 1, "no examples found in {}", dir.display());
}

#[test]
fn paper_example_has_the_papers_structure() {
    let bytes = std::fs::read(crate::root().join("examples/paper.lag")).unwrap();
    let model = crate::check_bytes(&bytes, "paper.lag").unwrap();
    let names: Vec<&str> = model.coords.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["q1", "q2"]);
    assert_eq!(model.constraint_order, Some(1));
    assert_eq!(model.independent(), [0]);
    assert_eq!(model.dependent(), [1]);
    let defaults: Vec<f64> = model.params.iter().map(|p| p.default).collect();
    assert_eq!(defaults, [1.0, 0.5]);
    assert_eq!(model.points.len(), 1);
    assert_eq!(model.initial.len(), 3);
    assert_eq!(model.forces.len(), 1);
}
