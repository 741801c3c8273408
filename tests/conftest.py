import matplotlib

matplotlib.use("Agg")


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """The fuzz suite's report (tests/test_fuzz.py): per category, the cases tried, the clean
    ones and the failing ones by kind; also written as JSON to $KINEMA_FUZZ_REPORT if set."""
    import json
    import os
    import sys

    cases, suite = sys.modules.get("fuzz_cases"), sys.modules.get("test_fuzz")
    if cases is None or suite is None or not getattr(cases, "REPORT", None):
        return
    failed = [r.nodeid.split("::")[-1].split("[")[0] for r in terminalreporter.stats.get("failed", []) if "test_fuzz.py" in r.nodeid]
    cases.mark_failed_tests(failed, suite.CATEGORY_OF)
    table = cases.report_table()
    terminalreporter.write_sep("=", "fuzz cases by category")
    terminalreporter.write_line(cases.format_report(table))
    where = os.environ.get("KINEMA_FUZZ_REPORT")
    if where:
        total = {k: sum(row[k] for row in table.values()) for k in ("tries", "clean", "failed")}
        with open(where, "w", encoding="utf-8") as f:
            json.dump({"examples": int(os.environ.get("KINEMA_FUZZ_EXAMPLES", "40")), "categories": table, "total": total}, f, indent=1)
        terminalreporter.write_line(f"(written to {where})")
