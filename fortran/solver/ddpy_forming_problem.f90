!> A forming problem as the core keeps it behind a handle (ddpy_handle_table): the blank and
!> the numbering of its unknowns, the tools, the pairs and the force-controlled tools (fixed
!> for the problem's life) with the Jacobian's layout computed from them, and what changes
!> per increment trial (the Newton settings, the increment's limits, the converged state it
!> starts from, where the tools are and the pairs' law); and what a trial gives (increment_answer,
!> increment_report). The static problem is one without tools. The api layer
!> (ddpy_api_forming) builds them; the Newton loop (ddpy_forming_newton) takes them whole.
module ddpy_forming_problem
  use ddpy_kinds, only: wp
  use ddpy_blank, only: blank_mesh, blank_dofs
  use ddpy_forming_data, only: tool_set, pair_set, force_holds, tool_placement, pair_law, &
                               increment_limits
  use ddpy_sparse, only: row_structure
  use ddpy_jacobian_layout, only: jacobian_layout
  implicit none
  private
  public :: forming_problem, newton_settings, increment_start, increment_answer, &
            increment_report

  !> Line searches: none (every step whole, halved only where an element fails);
  !> Deuflhard's natural monotonicity test with the residual-norm fallback (the forming
  !> problem's: the contact law has no potential); the energy line search, a secant on
  !> s(alpha) = du . r(u + alpha du) (a problem with a potential and a symmetric tangent).
  integer, parameter, public :: search_none = 0, search_monotonicity = 1, search_energy = 2
  !> What forming_increment returns (increment_report%outcome).
  integer, parameter, public :: outcome_converged = 0, outcome_landing = 1, &
                                outcome_element = 2, outcome_not_finite = 3, &
                                outcome_solver = 4, outcome_stalled = 5, outcome_hold = 6
  !> The rows of increment_report%history: per iteration its residual norm, relative
  !> residual, relative correction and the length of the step that led to it; and what
  !> changed since the previous iterate (0 at the start): the contact points whose
  !> pressure turned on or off, the pairs whose contact state (open, stick, slip) changed,
  !> and the blank's integration points that turned from elastic to plastic or back
  !> (plastic: a plastic strain above the increment's start); last, the relative error of
  !> the iterate that the convergence test judges (ddpy_forming_newton's estimated_error).
  integer, parameter, public :: history_width = 8, history_residual = 1, &
                                history_relative_residual = 2, &
                                history_relative_correction = 3, history_step = 4, &
                                history_points_switched = 5, history_pairs_switched = 6, &
                                history_yield_switched = 7, history_relative_error = 8
  !> Why a force-controlled tool lost the blank (increment_report%hold_reason): nothing
  !> holds it along its axis, or it moved farther than the search's reach in the increment.
  integer, parameter, public :: hold_no_stiffness = 1, hold_too_far = 2

  !> How the Newton loop runs an increment trial: the residual below force_tolerance times
  !> the force scale (at least floor, N) and the correction below displacement_tolerance
  !> times the motion, in max_iterations at most; the reuse of older factors by GMRES
  !> (reuse), its relative tolerance between krylov_tight and krylov_loose, krylov_max
  !> iterations at most and a factorization at the next correction after krylov_keep, and
  !> krylov_last: a correction that may be the last one leaves a linear residual of at most
  !> krylov_last times the force tolerance (Eisenstat and Walker's 0.1; docs/theory/
  !> linear-solver.md, "Tolerance"); the line search (search_*) and the residual ratio under which a whole step that changed
  !> contact states stands although it fails the monotonicity test (whole_step, <= 0: off).
  type :: newton_settings
    real(wp) :: force_tolerance = 0.0_wp, displacement_tolerance = 0.0_wp, floor = 0.0_wp
    integer :: max_iterations = 0
    logical :: reuse = .false.
    real(wp) :: krylov_loose = 1.0e-2_wp, krylov_tight = 1.0e-10_wp, krylov_last = 0.1_wp
    integer :: krylov_max = 12, krylov_keep = 8
    integer :: line_search = search_monotonicity
    real(wp) :: whole_step = 0.0_wp
    !> the contact search remembers each node's answer over an increment's evaluations
    logical :: search_memory = .false.
  end type newton_settings

  !> Where an increment starts and what drives it: the converged state of the blank (its
  !> displacements u_ref, the reference of the updated Lagrangian elements, and per Gauss
  !> point its material axes, stress, plastic strain, strain and, with mixed hardening, its
  !> backstress: nback = ne, else 0), the converged displacements u_n and pair forces
  !> force_n, the nodal loads, the values of the fixed dofs (u_n where supports hold) and,
  !> where has_guess, the start of the iterations.
  type :: increment_start
    real(wp), allocatable :: u_ref(:, :)                  !< (3, nnode)
    real(wp), allocatable :: axes_old(:, :, :, :)         !< (3, 3, 8, ne)
    real(wp), allocatable :: stress_old(:, :, :)          !< (6, 8, ne)
    real(wp), allocatable :: ep_old(:, :)                 !< (8, ne)
    real(wp), allocatable :: strain_old(:, :, :)          !< (6, 8, ne)
    real(wp), allocatable :: back_old(:, :, :)            !< (6, 8, nback)
    real(wp), allocatable :: u_n(:, :), external(:, :), prescribed(:, :), guess(:, :)
    real(wp), allocatable :: force_n(:, :)                !< (3, npair)
    logical :: has_guess = .false.
  end type increment_start

  !> A converged increment: the displacements, the pairs' forces, the internal forces, the
  !> blank's state, the pairs' contact states (inactive where off), gaps and normals, the
  !> Gauss points' tangential tractions and pressures, and each force-controlled tool's
  !> displacement along its axis.
  type :: increment_answer
    real(wp), allocatable :: u(:, :), force(:, :), fint(:, :)
    real(wp), allocatable :: stress(:, :, :), ep(:, :), strain(:, :, :), axes(:, :, :, :), &
                             back(:, :, :)
    integer, allocatable :: state(:)
    real(wp), allocatable :: gap(:), normal(:, :), traction(:, :), pressure(:), shift(:)
  end type increment_answer

  !> What a trial did: its outcome (outcome_*); per iteration (1..niter) its residual
  !> norm, relative residual, relative correction and the length of the step that led to
  !> it (history, 0 for the start); the work (evaluations, corrections, factorizations,
  !> Krylov iterations, line searches that ended on the residual-norm fallback) and its
  !> time in seconds per part; and, as the outcome says, the failing element's status and
  !> its index (1-based), the MUMPS code, the pairs that changed state in the last
  !> iteration (-1: unknown), the force-controlled tool that lost the blank with why
  !> (hold_*), the landing fraction, the last relative residual and correction.
  type :: increment_report
    integer :: outcome = -1, niter = 0
    real(wp), allocatable :: history(:, :)       !< (history_width, max_iterations + 1)
    integer :: evaluations = 0, corrections = 0, factorizations = 0, &
               krylov_iterations = 0, fallbacks = 0
    real(wp) :: assembly_time = 0.0_wp, contact_time = 0.0_wp, &
                factorization_time = 0.0_wp, solve_time = 0.0_wp
    integer :: element_status = 0, element = 0, solver_status = 0, flipped = 0, &
               hold_tool = 0, hold_reason = 0
    real(wp) :: landing = 1.0_wp, residual = 0.0_wp, correction = 0.0_wp
  end type increment_report

  !> The problem: fixed data, then what each trial sets. The Jacobian's layout (layout)
  !> and its structure by rows for GMRES (rows) are the core's, computed from the fixed
  !> data when first needed (ddpy_api_forming) and again when a tool or hold is added.
  type :: forming_problem
    type(blank_mesh) :: blank
    type(blank_dofs) :: dofs
    type(tool_set) :: tools
    type(pair_set) :: pairs
    type(force_holds) :: holds
    type(jacobian_layout) :: layout
    type(row_structure) :: rows
    !> A symmetric layout's entries (its one triangle's coordinates summed), which its
    !> solver is analysed with and factorizes; an unsymmetric one's are rows'.
    type(row_structure) :: entries
    !> Whether the settings and the limits of a trial were given.
    logical :: has_newton = .false., has_limits = .false.
    type(newton_settings) :: newton
    type(increment_limits) :: limits
    type(increment_start) :: start
    type(tool_placement) :: placement
    type(pair_law) :: law
  end type forming_problem

end module ddpy_forming_problem
