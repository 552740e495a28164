"""Pieces shared by the sub-commands, one module per concept; every name stays importable
from here (``from fcomp.cli.common import warn``):

=============================== ===========================================================
module                          what it holds
=============================== ===========================================================
:mod:`fcomp.cli.options`        the one vocabulary: shared options, deprecated spellings,
                                option values (``--set``, name lists, finite numbers)
:mod:`fcomp.cli.helptext`       plain-text help (:class:`HelpFormatter`)
:mod:`fcomp.cli.friction`       the friction model of the options (name or model file,
                                ``--params``, ``--add-effect``, ``--set``)
:mod:`fcomp.cli.targets`        the outputs, checked before any work
:mod:`fcomp.cli.emit`           what a command says: warnings, files written, its result
:mod:`fcomp.cli.display`        progress displays on a terminal
=============================== ===========================================================
"""

from __future__ import annotations

from fcomp.cli.display import (  # noqa: F401
    Activity,
    Progress,
)
from fcomp.cli.emit import (  # noqa: F401
    ARGV,
    OPTIONS,
    WARNINGS,
    WRITTEN,
    current_warnings,
    emit_result,
    in_cli_terms,
    python_warning,
    result_text,
    warn,
    warn_sidecar,
    with_warnings,
    write_measurement,
    wrote,
)
from fcomp.cli.friction import (  # noqa: F401
    build_model,
    friction_model,
    model_source,
    model_with_params,
    params_document,
    refuse_params_with_model_file,
    warn_fitted_range,
)
from fcomp.cli.helptext import (  # noqa: F401
    HelpFormatter,
    plain_text,
)
from fcomp.cli.options import (  # noqa: F401
    MAX_VALUE,
    PARAMS_HELP,
    SET_HELP,
    add_add_effect_option,
    add_closed_loop_run_options,
    add_effects_option,
    add_friction_option,
    add_length_options,
    add_model_options,
    add_option,
    add_parallel_options,
    add_params_option,
    add_progress_option,
    add_save_model_option,
    add_set_option,
    check_jobs,
    finite_float,
    name_list,
    parse_assignments,
    provided,
    say_deprecated,
)
from fcomp.cli.targets import (  # noqa: F401
    check_outputs,
    guard_outputs,
    json_target,
    measurement_inputs,
    model_target,
    output_path,
    plant_inputs,
    report_dir,
    save_model_file,
)
