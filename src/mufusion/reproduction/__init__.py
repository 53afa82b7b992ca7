"""The paper's experiments as data: variants, the paper's reported facts, verdicts, the report.

Figures stay in :mod:`mufusion.plots`; running the variants is :mod:`mufusion.campaign`'s job.
"""

from mufusion.reproduction.explain import explain_differences
from mufusion.reproduction.report import markdown_to_html, write_report
from mufusion.reproduction.specs import reproduction_specs
from mufusion.reproduction.variants import VARIANTS, Criterion, Variant, variant
from mufusion.reproduction.verdicts import Outcome, Verdict, compare_with_paper

__all__ = [
    "VARIANTS",
    "Criterion",
    "Outcome",
    "Variant",
    "Verdict",
    "compare_with_paper",
    "explain_differences",
    "markdown_to_html",
    "reproduction_specs",
    "variant",
    "write_report",
]
