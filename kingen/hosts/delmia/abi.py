"""The DELMIA V5 / IGRIP user-kinematics interface, declared once.

The stand-in ``shlibdefs.h``, the generated plugin's prototypes and the cffi
declarations used to load plugins are all rendered from these lists, so the C
side and the Python side cannot drift apart. Values are those of the vendor
header (docs/explanation/delmia-abi.md). The warnings are kingen's status codes (:mod:`kingen.kinematics.routine`).
"""

from ...kinematics.routine import INPUTS_MODIFIED, SINGULAR_TOLERANCE, UNWRITTEN_WARNING, WARNINGS

HEADER_VERSION = 1
"""Bumped when the stand-in header changes in a way generated sources rely on."""

WARNING_ALIASES = {"WARN_JOINT_LIMIT_EXCEEDED": "WARN_JOINT_LIMITS_EXCEEDED"}

CONSTANTS = {
    "USR_KIN_DATA_NULL": 0,
    "USR_KIN_DATA_KINSTAT": 1,
    "KIN_MODE_NORMAL": 0,
    "KIN_MODE_TRACK_TCP": 1,
    "KIN_MODE_OTHER": 2,
    "ROTATIONAL": 0,
    "TRANSLATIONAL": 1,
    "STATUS_OKAY": 0,
    "STATUS_ERROR": 1,
    "ZERO_TOL": SINGULAR_TOLERANCE,
}

KINSTAT_FIELDS = (
    ("int", "dof_count"),
    ("int *", "joint_types"),
    ("int", "kin_mode"),
    ("double *", "joint_values"),
    ("double *", "jnt_trvl_lmts[2]"),
    ("double", "mount_plate_offset[6]"),
    ("double", "curr_tool_offset[6]"),
)

KINSTAT_JOINT_TYPES = {"prismatic": "TRANSLATIONAL", "revolute": "ROTATIONAL"}
"""Joint type name (kingen.conventions.JointType.name) -> the vendor header's constant in
DLM_Data_KinStat.joint_types."""

GET_KIN_CONFIG = "int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint)"

HOST_MATH = {
    "sqrt": "double DNBVMAP_Sqrt(double x)",
    "asin": "double DNBVMAP_Asin(double x)",
    "acos": "double DNBVMAP_Acos(double x)",
    "atan": "double DNBVMAP_Atan(double x)",
    "atan2": "double DNBVMAP_Atan2(double y, double x)",
}
"""Math functions the vendor header maps to host symbols: (C name, host prototype)."""

HOST_CHECK = "int DNBVMAP_kin_check_definition(int dof_count, int solution_count)"

EMULATOR_FUNCTIONS = (
    "void kingen_host_reset(int dof_count, int solution_count)",
    "void kingen_host_refuse(int refuse)",
    "int kingen_host_check_calls(void)",
    "int kingen_host_last_dof(void)",
    "int kingen_host_last_solutions(void)",
    "void kingen_host_flush(void)",
    "int kingen_host_run_batch(void *routine, int count, double *t6, double *link_lengths, "
    "double *link_offsets, double *solutions, int solution_block, int *warnings, int warning_block, "
    "int *returns, void *pData)",
    "int kingen_host_run_guarded(void *routine, int count, double *t6, double *link_lengths, double *link_offsets, "
    "int dof, int postures, double *solutions, int *warnings, int *returns, int *faults, void *pData, "
    "const int *first_postures, const int *branch_of, double *branch_values, int *repeats)",
    "int kingen_host_summarise_branches(const double *solution, int dof, int postures, const int *first_postures, "
    "const int *branch_of, double *branch_values)",
)
"""Functions only the host emulator offers (state of kin_check_definition, batch drivers)."""
GUARD_FAULT_BITS = (
    ("KINGEN_WROTE_BEFORE_SOLUTIONS", 1, "wrote before solutions[0][0]"),
    ("KINGEN_WROTE_AFTER_SOLUTIONS", 2, "wrote past the end of solutions[][]"),
    ("KINGEN_WROTE_BEFORE_WARNINGS", 4, "wrote before warnings[0]"),
    ("KINGEN_WROTE_AFTER_WARNINGS", 8, "wrote past the end of warnings[]"),
    ("KINGEN_WROTE_INPUTS", INPUTS_MODIFIED, "modified its inputs (T6, link_lengths or link_offsets)"),
)
"""Bits kingen_host_run_guarded reports per call. Every bit but KINGEN_WROTE_INPUTS means
the call was stopped at the faulting write (its outputs are partial)."""
GUARD_FAULTS = {bit: text for _, bit, text in GUARD_FAULT_BITS}


def host_defines():
    """(macro, value) the host emulator is compiled with: sentinels and fault bits, from here."""
    return [("KINGEN_UNWRITTEN_WARNING", UNWRITTEN_WARNING),
            *((name, bit) for name, bit, _ in GUARD_FAULT_BITS)]


def routine_prototype(routine, solutions):
    """The routine's ANSI prototype; ``solutions`` is the column count (a number or a macro name)."""
    return (
        f"int {routine}(double link_lengths[], double link_offsets[], double T6[4][4], "
        f"double solutions[][{solutions}], int warnings[], void *pData)"
    )


def kinstat_struct():
    """The C declaration of DLM_Data_KinStat, field by field in the vendor's order."""
    fields = "".join(f"    {ctype} {name};\n" for ctype, name in KINSTAT_FIELDS)
    return f"typedef struct {{\n{fields}}} DLM_Data_KinStat;"


def cffi_declarations():
    """Everything cffi needs to drive a host emulator and plugins, except the routines."""
    prototypes = [GET_KIN_CONFIG, HOST_CHECK, *EMULATOR_FUNCTIONS]
    return kinstat_struct() + "\n" + "".join(f"{p};\n" for p in prototypes)


C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if "
    "inline int long register restrict return short signed sizeof static struct switch typedef "
    "union unsigned void volatile while _Alignas _Alignof _Atomic _Bool _Complex _Generic "
    "_Imaginary _Noreturn _Static_assert _Thread_local __declspec __cdecl __stdcall".split()
)


def _declared_name(prototype):
    return prototype.split("(")[0].split()[-1].lstrip("*")


HOST_SYMBOLS = (_declared_name(HOST_CHECK), *(_declared_name(prototype) for prototype in HOST_MATH.values()))
"""The symbols a plugin imports from the host process (the vendor header maps kin_check_definition
and the math functions to them): on Windows, DELMIA's import library resolves them at link time."""

RESERVED_NAMES = frozenset({
    *C_KEYWORDS, *WARNINGS, *WARNING_ALIASES, *CONSTANTS, "DllExport", "DLM_Data_KinStat",
    "kin_check_definition", _declared_name(GET_KIN_CONFIG), *HOST_SYMBOLS, *HOST_MATH,
    *(_declared_name(prototype) for prototype in EMULATOR_FUNCTIONS),
    "kin_routine", "kin_dof",
})
"""Names a generated routine or library may not take: C keywords and everything the vendor
header (and so kingen's stand-in) defines, the parameters of get_kin_config included."""
