"""The diagnosis study's pieces on two cases: one hidden effect and the out-of-catalogue drift."""
from doe_calib import Robot, Tool, examples
from studies.diagnosis.report import markdown
from studies.diagnosis.study import one_case


def test_study_case_finds_the_hidden_effect_and_reports_the_drift():
    robot, tool = Robot.from_urdf(examples.ROBOT_URDF), Tool.from_yaml(examples.TOOL_YAML)
    found = one_case(robot, tool, "gear_ratio(j3)", "joint_offset+joint_compliance", seed=5)
    assert found["rank_of_hidden"] == 1 and found["top"] == "gear_ratio(j3)"
    assert found["validation_rms_with_top_mm"] <= 1.2 * found["validation_rms_true_model_mm"]
    drift = one_case(robot, tool, None, "joint_offset+joint_compliance", seed=6, drift_m=0.002)
    assert drift["hidden"] == "tracker drift" and not drift["adequate"]
    assert drift["follows"] == "measurement order" and drift["proposed"] is None
    text = markdown({"robot": robot.name, "sigma_mm": 0.03, "cases": [found, drift],
                     "refine": {"truth": "x", "steps": [], "stopped": "s",
                                "validation_rms_true_model_mm": 0.03}})
    assert "gear_ratio(j3) (1)" in text and "tracker drift" in text
    assert "(not proposed)" in text or "(n.s.)" in text
