!> The Newton loop of one increment: the blank's displacements and the contact forces of
!> every (tool, slave) pair solved together, DD3IMP's single loop (docs/theory/contact.md);
!> with no tools, the static problem of a solid under prescribed displacements and loads.
!> Each evaluation assembles the blank (ddpy_solid_assembly) and the contact of every tool
!> (ddpy_forming); each correction is solved with MUMPS, or by GMRES on older factors while
!> they serve; the step is limited where free nodes would enter a tool and globalized by
!> Deuflhard's natural monotonicity test. The problem arrives in the derived types of
!> ddpy_forming_problem, built by the api layer.
!>
!> Unknowns: the free displacement dofs (eqn), then 3 force components per pair. Weights
!> make them all lengths: 1 for displacements, 1 / r for the forces.
module ddpy_forming_newton
  use, intrinsic :: iso_fortran_env, only: int64
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
  use ddpy_kinds, only: wp
  use ddpy_material, only: yield_landing, material_kinematic
  use ddpy_solid_assembly, only: solid_assemble, shell_modes
  use ddpy_blank, only: blank_mesh, blank_dofs
  use ddpy_forming_data, only: tool_set, pair_set, force_holds, tool_placement, pair_law, &
                               increment_limits, contact_node, has_barrier, node_point
  use ddpy_forming_problem, only: newton_settings, increment_start, increment_answer, &
                                  increment_report, search_none, search_energy, &
                                  outcome_converged, outcome_landing, outcome_element, &
                                  outcome_not_finite, outcome_solver, outcome_stalled, &
                                  outcome_hold, hold_no_stiffness, hold_too_far, &
                                  history_width, history_residual, history_relative_residual, &
                                  history_relative_correction, history_step, &
                                  history_points_switched, history_pairs_switched, &
                                  history_yield_switched, history_relative_error
  use ddpy_forming, only: forming_contact
  use ddpy_global_search, only: memory_rows
  use ddpy_contact, only: contact_inactive
  use ddpy_linear_solver, only: solver_factorize, solver_solve, solver_precision, &
                                precision_single, status_single_too_coarse
  use ddpy_sparse, only: sum_duplicates, row_structure
  use ddpy_jacobian_layout, only: jacobian_layout
  implicit none
  private
  public :: forming_increment, penetration_step, gmres, hold_equations

  !> Pairs are held on their patches after 1/hold_fraction of the iterations
  !> (forming_increment); the answer's gaps may then differ from the search's by
  !> hold_depth element sizes. An answer the search refuses is held again on the search's
  !> patches, at most hold_limit times in an increment.
  integer, parameter :: hold_fraction = 3, hold_limit = 3
  real(wp), parameter :: hold_depth = 1.0e-4_wp
  !> MUMPS's INFOG(1) for a numerically singular matrix.
  integer, parameter :: mumps_numerically_singular = -10
  !> GMRES on fresh single-precision factors where the loop solves exactly (a careful start,
  !> the springback): its relative tolerance and most iterations. The factors alone leave
  !> about eps_single times the condition number, 0.15 to 0.25 along the sheet's soft
  !> bending modes on the paper bending blank; each GMRES step divides that by about four.
  real(wp), parameter :: single_exact_tolerance = 1.0e-8_wp
  integer, parameter :: single_exact_iterations = 30
  !> delta of the perturbed Lagrangian that factors a Jacobian singular in its
  !> multipliers (direction): a penalty r / delta, delta near the square root of the
  !> unit roundoff, so that the step's error in the determined unknowns stays near delta.
  real(wp), parameter :: multiplier_perturbation = 1.0e-8_wp
  !> A force-controlled tool with no contact stiffness along its axis is moved onto its
  !> nearest slave, touch_depth element sizes into it, at most hold_retouches times in an
  !> increment (forming_increment).
  integer, parameter :: hold_retouches = 3
  real(wp), parameter :: touch_depth = 1.0e-3_wp

contains

  !> Newton iterations of one increment from the converged state (start: u_n, force_n, the
  !> solid state *_old of the blank's mesh, see solid_assemble) to the tools at
  !> placement%positions and the fixed dofs at start%prescribed (forming holds them at
  !> u_n), in the loop's settings (newton) and the increment's limits, the Jacobian's
  !> layout (ddpy_jacobian_layout: its coordinate slots, which pairs' multipliers are
  !> eliminated, the coupling entries' values), its structure by rows (rows, for GMRES)
  !> and, for a symmetric layout, the entries of its triangle (entries, unused otherwise):
  !> the solver factorizes the coordinates summed into the entries it was analysed with,
  !> rows' for an unsymmetric layout (ddpy.model.newton.Layout.entries). A prescribed
  !> motion not yet reached enters each evaluation through the tangent, K_fp dp added to
  !> the free rows, and each step takes it whole (scaled by the step length like the
  !> rest): the linearized predictor, not a jump of the boundary nodes, which would invert
  !> the elements next to them. See forming_contact for the tools and pairs. Returns the
  !> report (outcome, history, work, and why it failed) and, when converged, the answer:
  !> u, force, the solid state, the internal forces fint, the contact states (inactive
  !> where off), gaps, normals and the Gauss points' tractions and pressures.
  !> factored, reuse_next: the solver's factors are this layout's, the last GMRES
  !> converged fast (solver: the MUMPS handle, analysed for the structure).
  !> The solid-shell's enhanced parameters live in the evaluations like the trial state:
  !> each evaluation starts its local iteration from those of the iterate the step leaves
  !> (zero at the start of the increment), so an evaluation is a function of the iterate
  !> and its start, not of the line search's earlier trials. The backstress of mixed
  !> hardening (nback = ne; without kinematic hardening not read, and back = back_old)
  !> is carried like the stress.
  !>
  !> Force-controlled tools (holds, docs/theory/contact.md): tool holds%tool(k) sits at
  !> positions + shift(k) holds%axis(:, k), shift(k) one more unknown (after the pairs'
  !> forces), whose equation is sum over the tool's pairs of axis . lambda =
  !> placement%hold_force(k), the force the tool presses on the blank with. Its Jacobian
  !> entries follow the contact blocks (ddpy_jacobian_layout): per tool, its column (the
  !> rows of its pairs' laws, or a Gauss-point pair's free equilibrium rows), its row
  !> (holds%first(k) + 1 .. holds%first(k + 1): holds%coef times the value at slot
  !> holds%source (0-based), or holds%coef alone where the source < 0), its diagonal. A
  !> step moves a tool by at most
  !> limits%hold_step; outcome_hold when a tool has no contact stiffness along its axis or
  !> has moved farther than the reach in the increment.
  subroutine forming_increment(blank, dofs, layout, rows, entries, tools, pairs, holds, &
                               newton, limits, start, placement, law, solver, factored, &
                               reuse_next, answer, report)
    type(blank_mesh), intent(in) :: blank
    type(blank_dofs), intent(in) :: dofs
    type(jacobian_layout), intent(in) :: layout
    type(row_structure), intent(in) :: rows, entries
    integer, intent(in) :: solver
    type(tool_set), intent(in) :: tools
    type(pair_set), intent(in) :: pairs
    type(force_holds), intent(in) :: holds
    type(newton_settings), intent(in) :: newton
    type(increment_limits), intent(in) :: limits
    type(increment_start), intent(in) :: start
    type(tool_placement), intent(in) :: placement
    type(pair_law), intent(in) :: law
    integer, intent(inout) :: factored, reuse_next
    type(increment_answer), intent(inout) :: answer
    type(increment_report), intent(out) :: report

    !> One evaluation: the iterate and what was evaluated there.
    type :: evaluation
      real(wp), allocatable :: u(:, :), force(:, :), residual(:), values(:), fint(:, :), &
                               stress(:, :, :), ep(:, :), strain(:, :, :), axes(:, :, :, :), &
                               back(:, :, :), alpha(:, :), gap(:), normal(:, :), simplified(:), &
                               traction(:, :), pressure(:), shift(:), dc_dt(:, :, :), &
                               stiffness(:), lumped(:, :), barrier_dt(:, :, :)
      integer, allocatable :: state(:), patch(:)
      logical :: moving  ! some fixed dof short of its prescribed value
      real(wp) :: rest   ! how far short: the norm over the fixed dofs
    end type evaluation
    type(evaluation) :: slot(2)
    real(wp), allocatable :: weight(:), delta(:), du(:, :), dforce(:, :), x_n(:, :), &
                             kdu(:, :), dp(:, :), u_cur(:, :), force_cur(:, :), &
                             alpha_cur(:, :), shift_cur(:), dshift(:), summed(:)
    integer, allocatable :: previous(:), lock(:), memory_patch(:)
    ! The contact search's memory of every pair's node and Gauss point over the trial's
    ! evaluations (ddpy_global_search.contact_search; none when newton%search_memory is off).
    real(wp), allocatable :: memory(:, :)
    logical, allocatable :: averaged(:)
    ! The sets of the last recorded iterate and of the one before it (record): the contact
    ! points carrying pressure, the pairs' states, the plastic integration points.
    logical, allocatable :: on_last(:), on_before(:), yield_last(:, :), yield_before(:, :)
    integer, allocatable :: state_last(:), state_before(:)
    integer :: sets_niter
    integer :: tool, k, hold_base, retouches, nvalues
    logical :: retouched
    real(wp) :: tol_force, tol_disp, yield_tol, floor, norm, scale, moved, correction, rel, &
                forcing, alpha, step_size, du_norm, landing, t_norm, t_scale, t_moved, &
                alpha_fallback, whole_step, size_ratio, element_size, correction_before, &
                infinity
    ! Whether the step that led to the iterate (correction) was a whole Newton step; the
    ! step before it (correction_before) is kept only where it was one, else +inf: the
    ! error estimate (estimated_error) needs both whole.
    logical :: whole
    integer :: max_iterations, cur, trial, fallback, buffer, iteration, ls, n, status, &
               element, last_status, last_element, hold_after, hold_count
    logical :: converged, have_previous, have_hint, accepted, t_converged, moving, &
               held_on_patches
    integer :: search, nnode, ne, nback, nf, k_slots, n_coupling, ntool, npair, npoint, nhold
    integer :: precision
    logical :: single  ! the solver's factors are single precision
    integer(int64) :: clock_rate
    ! An explicit-shape copy of u_n: the motion's norm (measure) is then summed by the same
    ! compiled loop as when u_n was an argument of its own; over the component, the
    ! compiler fuses other terms into multiply-adds, and the correction's ratio to the
    ! motion moved in its last bit.
    real(wp) :: u_n(3, blank%nnode)

    u_n = start%u_n
    nnode = blank%nnode
    ne = blank%ne
    nback = size(start%back_old, 3)
    nf = dofs%nf
    k_slots = dofs%k_slots
    ntool = tools%ntool
    npair = pairs%npair
    npoint = tools%npoint
    nhold = holds%nhold
    nvalues = layout%nvalues
    n_coupling = layout%ncoupling
    element_size = limits%element_size
    call system_clock(count_rate=clock_rate)
    call solver_precision(solver, precision, status)
    single = status == 0 .and. precision == precision_single
    tol_force = newton%force_tolerance
    tol_disp = newton%displacement_tolerance
    yield_tol = limits%yield_tolerance
    floor = newton%floor
    whole_step = newton%whole_step
    size_ratio = max(limits%size_ratio, 1.0_wp)
    max_iterations = newton%max_iterations
    hold_after = max(2, max_iterations/hold_fraction)
    search = newton%line_search
    n = nf + 3*npair + nhold
    retouches = 0
    report = increment_report()
    allocate(report%history(history_width, max_iterations + 1))
    report%history = 0.0_wp
    report%outcome = outcome_stalled
    answer%shift = 0.0_wp
    allocate(weight(n), delta(n), du(3, nnode), dforce(3, npair), x_n(3, nnode), &
             kdu(3, nnode), dp(3, nnode), previous(npair), u_cur(3, nnode), &
             force_cur(3, npair), alpha_cur(shell_modes, ne), lock(npair + npoint), &
             shift_cur(nhold), dshift(nhold))
    alpha_cur = 0.0_wp
    lock = 0
    if (newton%search_memory) then
      allocate(memory(memory_rows, npair + npoint), memory_patch(npair + npoint))
    else
      allocate(memory(memory_rows, 0), memory_patch(0))
    end if
    memory_patch = -1
    allocate(on_last(npoint), on_before(npoint), yield_last(8, ne), yield_before(8, ne), &
             state_last(npair), state_before(npair))
    sets_niter = 0
    held_on_patches = .false.
    hold_count = 0
    dp = 0.0_wp
    step_size = 0.0_wp
    weight(1:nf) = 1.0_wp
    weight(nf + 1:nf + 3*npair) = reshape(spread(1.0_wp/law%r, 1, 3), [3*npair])
    weight(nf + 3*npair + 1:) = 1.0_wp  ! the tools' shifts are lengths
    ! Pairs whose gap averages Gauss points' (held_ok checks the points instead).
    allocate(averaged(npair))
    do tool = 1, ntool
      averaged(pairs%tool_first(tool) + 1:pairs%tool_first(tool + 1)) = &
        tools%tool(tool)%discretization /= contact_node
    end do
    ! The force-controlled tools' entries close the values.
    hold_base = layout%contact_values
    x_n = blank%x0 + start%u_n
    do cur = 1, 2
      allocate(slot(cur)%u(3, nnode), slot(cur)%force(3, npair), slot(cur)%residual(n), &
               slot(cur)%values(nvalues), slot(cur)%fint(3, nnode), &
               slot(cur)%stress(6, 8, ne), slot(cur)%ep(8, ne), slot(cur)%strain(6, 8, ne), &
               slot(cur)%axes(3, 3, 8, ne), slot(cur)%alpha(shell_modes, ne), &
               slot(cur)%gap(npair), slot(cur)%normal(3, npair), &
               slot(cur)%simplified(n), slot(cur)%state(npair), &
               slot(cur)%patch(npair + npoint), &
               slot(cur)%traction(3, npoint), slot(cur)%pressure(npoint), &
               slot(cur)%back(6, 8, nback), slot(cur)%shift(nhold), &
               slot(cur)%dc_dt(3, 3, npair), slot(cur)%stiffness(nhold), &
               slot(cur)%lumped(3, npair), slot(cur)%barrier_dt(3, 3, npair))
      slot(cur)%back = start%back_old
      slot(cur)%values(k_slots + 1:k_slots + n_coupling) = layout%coupling
      slot(cur)%shift = 0.0_wp
    end do
    infinity = ieee_value(1.0_wp, ieee_positive_inf)
    correction = infinity
    correction_before = infinity
    whole = .false.
    alpha = 0.0_wp
    have_hint = .false.
    have_previous = .false.
    ! The extrapolated start, unless an element fails there; else the converged state.
    cur = 1
    status = 1
    if (start%has_guess) then
      slot(cur)%u = start%guess
      slot(cur)%force = start_force()
      call evaluate(slot(cur), limits%touching, status, element)
    end if
    if (status /= 0) then
      slot(cur)%u = start%u_n
      slot(cur)%force = start_force()
      call evaluate(slot(cur), limits%touching, status, element)
      if (status /= 0) then
        report%outcome = outcome_element
        report%element_status = status
        report%element = element
        return
      end if
    end if
    do iteration = 0, max_iterations
      report%niter = report%niter + 1
      call record(slot(cur))
      report%history(history_step, report%niter) = alpha
      if (.not. ieee_is_finite(norm)) then
        report%outcome = outcome_not_finite
        return
      end if
      do while (converged .and. held_on_patches)
        held_on_patches = .false.
        if (.not. held_ok(slot(cur), slot(3 - cur))) then
          ! The search disagrees with the held answer: the iterations go on from the same
          ! iterate (slot 3 - cur holds its evaluation without the hold), and it stands if
          ! the free equations are already met there; else they go on held on the
          ! search's patches there, which the next answer is checked against in turn.
          cur = 3 - cur
          call record(slot(cur))
          if (.not. converged .and. hold_count < hold_limit .and. iteration < max_iterations) then
            call hold(slot(cur))
            if (report%outcome == outcome_element) return
          end if
        end if
      end do
      if (converged) then
        call finish(slot(cur))
        return
      end if
      if (iteration == hold_after .and. iteration < max_iterations) then
        ! Nodes (or Gauss points) that hop between the facets of an edge keep this
        ! increment from converging: from here each stays on the patch it has
        ! (docs/theory/contact.md), and the answer is checked against the search.
        call hold(slot(cur))
        if (report%outcome == outcome_element) return
      end if
      if (iteration == max_iterations) then
        report%outcome = outcome_stalled
        report%residual = norm/scale
        report%correction = correction/moved
        report%flipped = -1
        if (have_previous) report%flipped = count(law%on /= 0 .and. slot(cur)%state /= previous)
        return
      end if
      ! Inexact Newton (Eisenstat and Walker): the correction's relative error may be a
      ! tenth of the relative residual (the rate stays quadratic), or as large as leaves
      ! the next residual krylov_last times the tolerance (the last iteration).
      retouched = .false.
      do k = 1, nhold
        ! A tool that nothing holds along its axis would take a singular step, or one
        ! that flies it off: it is brought back onto the blank (its iterate moved off a
        ! contact of a few hundredths of a micrometre), at most hold_retouches times in
        ! an increment; else the increment stops and says which.
        if (slot(cur)%stiffness(k) > 0.0_wp) cycle
        if (retouches < hold_retouches) then
          if (retouch(slot(cur), k)) then
            retouched = .true.
            cycle
          end if
          if (report%outcome == outcome_element) return
        end if
        report%outcome = outcome_hold
        report%hold_tool = holds%tool(k)
        report%hold_reason = hold_no_stiffness
        return
      end do
      if (retouched) then
        retouches = retouches + 1
        whole = .false.  ! the iterate moved without a Newton step
        alpha = 0.0_wp
        cycle
      end if
      rel = norm/scale
      forcing = min(newton%krylov_loose, max(newton%krylov_tight, 0.1_wp*rel, &
                                     newton%krylov_last*tol_force/max(rel, 1.0e-300_wp)))
      report%corrections = report%corrections + 1
      call direction(slot(cur), forcing, step_size, status)
      if (status < 0) then
        report%outcome = outcome_solver
        report%solver_status = status
        return
      end if
      du = 0.0_wp
      call scatter(delta(1:nf), du)
      if (slot(cur)%moving) then
        ! The prescribed rest is part of the step (its constraint rows are solved exactly),
        ! and of the step's length that the line search compares against.
        where (dofs%fixed) du = start%prescribed - slot(cur)%u
        step_size = hypot(step_size, slot(cur)%rest)
      end if
      dforce = reshape(delta(nf + 1:nf + 3*npair), [3, npair])
      dshift = delta(nf + 3*npair + 1:)
      du_norm = sqrt(dot_product(delta(1:nf), delta(1:nf)) + dot_product(dshift, dshift))
      ! The factors hold this iteration's Jacobian from here. The first trial stops short
      ! where the step would push a free node into a tool.
      alpha = penetration_step(nnode, npair, du, pairs%node, law%on, slot(cur)%state, &
                               slot(cur)%gap, slot(cur)%normal, limits%penetration*element_size, &
                               limits%min_step)
      if (nhold > 0) then
        ! A force-controlled tool moves at most limits%hold_step in a step.
        if (maxval(abs(dshift))*alpha > limits%hold_step) &
          alpha = limits%hold_step/maxval(abs(dshift))
      end if
      previous = slot(cur)%state
      have_previous = .true.
      moving = slot(cur)%moving
      u_cur = slot(cur)%u
      force_cur = slot(cur)%force
      shift_cur = slot(cur)%shift
      alpha_cur = slot(cur)%alpha
      fallback = 0
      buffer = 1
      accepted = .false.
      have_hint = .false.
      if (search == search_energy) then
        call energy_step(moving .or. iteration == 0, &
                         dot_product(delta(1:nf), slot(cur)%residual(1:nf)), alpha, trial, &
                         last_status, last_element)
        accepted = .true.
      end if
      do ls = 1, 5
        if (accepted) exit
        trial = buffer
        call try_step(slot(trial), alpha, moving, last_status, last_element)
        if (last_status == 0) then
          if (search == search_none) then
            accepted = .true.
            exit
          end if
          if (alpha == 1.0_wp) then
            call measure(slot(trial), estimated_error(du_norm, merge(correction, infinity, &
                         whole)), t_norm, t_scale, t_moved, t_converged)
            if (t_converged) then  ! converged: the next iteration returns it
              accepted = .true.
              exit
            end if
          end if
          ! Natural monotonicity test (Deuflhard): the simplified Newton correction at
          ! the trial, with this iteration's factors, must be shorter than the step's.
          call timed_solve(-slot(trial)%residual, slot(trial)%simplified, status)
          if (status < 0) then
            report%outcome = outcome_solver
            report%solver_status = status
            return
          end if
          if (hypot(weighted_norm(slot(trial)%simplified), slot(trial)%rest) <= &
              (1.0_wp - alpha/4.0_wp)*step_size) then
            accepted = .true.
            have_hint = .true.
            exit
          end if
          t_norm = sqrt(dot_product(slot(trial)%residual, slot(trial)%residual))
          ! The simplified correction is computed with this iteration's contact set, so a
          ! pair that changes state in the step makes it long however good the step: a
          ! whole step that changed some pairs and cut the residual enough stands.
          if (alpha == 1.0_wp .and. t_norm <= whole_step*norm) then
            ! (Against the iterate's states as saved: slot(cur) may be the trial's own.)
            if (any(law%on /= 0 .and. slot(trial)%state /= previous)) then
              accepted = .true.
              have_hint = .true.
              exit
            end if
          end if
          if (fallback == 0 .and. t_norm <= (1.0_wp - 1.0e-4_wp*alpha)*norm) then
            fallback = trial
            alpha_fallback = alpha
            buffer = 2  ! the fallback keeps its evaluation in slot 1
          end if
        end if
        alpha = 0.5_wp*alpha
      end do
      if (.not. accepted) then
        ! The simplified correction sees the contact set of this iteration: where that set
        ! changes, the test can fail at every step length. Then the longest step that
        ! lowered the residual norm, if one did, else the last.
        if (fallback /= 0) then
          trial = fallback
          alpha = alpha_fallback
          last_status = 0
          report%fallbacks = report%fallbacks + 1
        else
          alpha = 2.0_wp*alpha
        end if
        have_hint = .true.
      end if
      if (last_status /= 0) then
        report%outcome = outcome_element
        report%element_status = last_status
      report%element = last_element
        return
      end if
      cur = trial
      correction_before = merge(correction, infinity, whole)
      whole = alpha == 1.0_wp
      correction = alpha*du_norm
      do k = 1, nhold
        if (abs(slot(cur)%shift(k)) > limits%reach) then
          report%outcome = outcome_hold
          report%hold_tool = holds%tool(k)
          report%hold_reason = hold_too_far
          return
        end if
      end do
      if (yield_tol >= 0.0_wp .and. alpha == 1.0_wp) then
        ! The elastic predictor is the first full Newton step: a step shortened by the
        ! line search or the penetration limit starts from a poor iterate, whose strains
        ! say little of where the converged path yields.
        if (material_kinematic(blank%props) .and. nback == ne) then
          ! The elastic path of the relative stress: the backstress stays while elastic.
          landing = yield_landing(blank%props, 8*ne, start%stress_old - start%back_old, &
                                  start%ep_old, slot(cur)%strain - start%strain_old, &
                                  yield_tol)
        else
          landing = yield_landing(blank%props, 8*ne, start%stress_old, start%ep_old, &
                                  slot(cur)%strain - start%strain_old, yield_tol)
        end if
        yield_tol = -1.0_wp
        if (landing < 1.0_wp) then
          report%outcome = outcome_landing
          report%landing = landing
          return
        end if
      end if
    end do

  contains
    !> u_cur + alpha (du, dforce) into slot s, evaluated; the prescribed values exactly at
    !> a whole step.
    subroutine try_step(s, alpha, moving, status, element)
      type(evaluation), intent(inout) :: s
      real(wp), intent(in) :: alpha
      logical, intent(in) :: moving
      integer, intent(out) :: status, element
      s%u = u_cur + alpha*du
      if (alpha == 1.0_wp .and. moving) then
        where (dofs%fixed) s%u = start%prescribed
      end if
      s%force = force_cur + alpha*dforce
      s%shift = shift_cur + alpha*dshift
      call evaluate(s, 0.0_wp, status, element)
    end subroutine try_step

    !> The energy line search from the iterate whose s(0) = du . r is s0: the step whole
    !> (halved up to 3 times where an element fails) unless it overshoots, s(1) > 0 and
    !> above half of |s(0)|; then secant steps on s, kept within the bracket, until |s| is
    !> at most half of |s(0)| (at most 5). The predictor, the first correction of the
    !> increment, is taken whole (``whole``): it is linearized at the converged state, its
    !> overshoot what the next iterations correct (on a bending sheet, a membrane residual
    !> of second order that the secant would cut to half the bending step); and so is a
    !> step that carries prescribed motion, whose residual holds the linearized K dp, not
    !> a gradient of the energy. The evaluation of the step taken is in slot 1 (trial).
    subroutine energy_step(whole, s0, alpha, trial, status, element)
      logical, intent(in) :: whole
      real(wp), intent(in) :: s0
      real(wp), intent(inout) :: alpha
      integer, intent(out) :: trial, status, element
      real(wp) :: lo, hi, s_lo, s_hi, s
      integer :: k
      trial = 1
      do k = 1, 4
        call try_step(slot(trial), alpha, moving, status, element)
        if (status == 0) exit
        alpha = 0.5_wp*alpha
      end do
      if (status /= 0 .or. whole) return
      s = dot_product(delta(1:nf), slot(trial)%residual(1:nf))
      if (.not. (s0 < 0.0_wp .and. s > 0.0_wp .and. s > -0.5_wp*s0)) return
      lo = 0.0_wp
      s_lo = s0
      hi = alpha
      s_hi = s
      do k = 1, 5
        alpha = hi - s_hi*(hi - lo)/(s_hi - s_lo)
        alpha = min(max(alpha, lo + 0.1_wp*(hi - lo)), hi - 0.1_wp*(hi - lo))
        call try_step(slot(trial), alpha, .false., status, element)
        if (status /= 0) then
          hi = alpha
          s_hi = abs(s_hi)
          cycle
        end if
        s = dot_product(delta(1:nf), slot(trial)%residual(1:nf))
        if (abs(s) <= -0.5_wp*s0) exit
        if (s > 0.0_wp) then
          hi = alpha
          s_hi = s
        else
          lo = alpha
          s_lo = s
        end if
      end do
    end subroutine energy_step

    !> Assembly and contact at s%u, s%force into slot s; the enhanced parameters start at
    !> alpha_cur.
    subroutine evaluate(s, touching_gap, status, element)
      type(evaluation), intent(inout) :: s
      real(wp), intent(in) :: touching_gap
      integer, intent(out) :: status, element
      integer(int64) :: t0, t1, t2
      integer :: a, c, p, k
      real(wp) :: placed(3, ntool)
      report%evaluations = report%evaluations + 1
      call system_clock(t0)
      where (dofs%fixed)
        dp = start%prescribed - s%u
      elsewhere
        dp = 0.0_wp
      end where
      s%moving = any(dp /= 0.0_wp)
      s%rest = 0.0_wp
      if (s%moving) s%rest = sqrt(sum(dp**2))
      call solid_assemble(nnode, blank%x0, ne, blank%conn, blank%kind, start%u_ref, s%u, &
                          blank%props, start%axes_old, start%stress_old, start%ep_old, &
                          start%strain_old, nback, start%back_old, alpha_cur, dofs%eqn, &
                          dofs%symmetric, .true., dofs%offsets, k_slots, s%values(1:k_slots), &
                          s%moving, dp, s%fint, kdu, s%stress, s%ep, s%strain, s%axes, &
                          s%back, s%alpha, status, element)
      call system_clock(t1)
      report%assembly_time = report%assembly_time + real(t1 - t0, wp)/real(clock_rate, wp)
      if (status /= 0) return
      do a = 1, nnode
        do c = 1, 3
          if (dofs%eqn(c, a) >= 0) s%residual(dofs%eqn(c, a) + 1) = s%fint(c, a) - &
                                                                 start%external(c, a)
        end do
      end do
      if (s%moving) then  ! the linearized rest of the prescribed motion
        do a = 1, nnode
          do c = 1, 3
            if (dofs%eqn(c, a) >= 0) s%residual(dofs%eqn(c, a) + 1) = &
              s%residual(dofs%eqn(c, a) + 1) + kdu(c, a)
          end do
        end do
      end if
      placed = placement%positions
      do k = 1, nhold
        placed(:, holds%tool(k)) = placed(:, holds%tool(k)) + s%shift(k)*holds%axis(:, k)
      end do
      call forming_contact(blank%x0 + s%u, x_n, dofs, tools, pairs, law, placed, &
                           placement%positions_n, limits, touching_gap, s%force, lock, &
                           size(memory_patch), memory, memory_patch, &
                           nvalues, s%residual, s%values, s%state, s%gap, s%normal, &
                           s%traction, s%pressure, s%patch, s%dc_dt, s%lumped, s%barrier_dt)
      ! A Gauss-point pair's multiplier is eliminated: lambda = F(x), C = 0.
      do p = 1, npair
        if (.not. layout%eliminated(p)) cycle
        s%force(:, p) = s%force(:, p) - s%residual(nf + 3*p - 2:nf + 3*p)
        s%residual(nf + 3*p - 2:nf + 3*p) = 0.0_wp
      end do
      call hold_equations(dofs, pairs, law%on, holds, placement%hold_force, &
                          layout%eliminated, layout%barrier, s%force, s%lumped, s%dc_dt, &
                          s%barrier_dt, hold_base, s%residual(nf + 3*npair + 1:), &
                          s%values, s%stiffness)
      call system_clock(t2)
      report%contact_time = report%contact_time + real(t2 - t1, wp)/real(clock_rate, wp)
    end subroutine evaluate

    !> Moves force-controlled tool k of slot s along its axis onto its nearest slave (by
    !> the gaps along the tool's normals at the pairs' closest points), touch_depth
    !> element sizes into it, and evaluates s there; false where no slave within the
    !> search's reach faces it or an element fails (the report then says so).
    logical function retouch(s, k)
      type(evaluation), intent(inout) :: s
      integer, intent(in) :: k
      real(wp) :: closing, travel
      integer :: p, status, element
      retouch = .false.
      travel = huge(1.0_wp)
      do p = pairs%tool_first(holds%tool(k)) + 1, pairs%tool_first(holds%tool(k) + 1)
        if (law%on(p) == 0 .or. .not. ieee_is_finite(s%gap(p))) cycle
        closing = dot_product(s%normal(:, p), holds%axis(:, k))
        if (closing > 0.5_wp) travel = min(travel, s%gap(p)/closing)
      end do
      if (travel == huge(1.0_wp)) return
      s%shift(k) = s%shift(k) + travel + touch_depth*element_size
      call evaluate(s, 0.0_wp, status, element)
      if (status /= 0) then
        report%outcome = outcome_element
        report%element_status = status
        report%element = element
        return
      end if
      retouch = .true.
    end function retouch

    !> measure for slot s, as this iteration's history (residual, relative residual and
    !> correction), with what changed since the previous iterate: contact points on or
    !> off, pairs' states, integration points between elastic and plastic. An iterate
    !> recorded again (the held answer's evaluation without the hold) is compared with the
    !> same previous iterate.
    subroutine record(s)
      type(evaluation), intent(in) :: s
      real(wp) :: error
      error = estimated_error(correction, merge(correction_before, infinity, whole))
      call measure(s, error, norm, scale, moved, converged)
      report%history(history_residual, report%niter) = norm
      report%history(history_relative_residual, report%niter) = norm/scale
      report%history(history_relative_correction, report%niter) = correction/moved
      report%history(history_relative_error, report%niter) = error/moved
      if (report%niter > sets_niter) then
        if (sets_niter > 0) then
          on_before = on_last
          state_before = state_last
          yield_before = yield_last
        end if
        sets_niter = report%niter
      end if
      on_last = s%pressure > 0.0_wp
      state_last = s%state
      yield_last = s%ep > start%ep_old
      if (report%niter == 1) return
      report%history(history_points_switched, report%niter) = &
        real(count(on_last .neqv. on_before), wp)
      report%history(history_pairs_switched, report%niter) = &
        real(count(state_last /= state_before), wp)
      report%history(history_yield_switched, report%niter) = &
        real(count(yield_last .neqv. yield_before), wp)
    end subroutine record

    !> Residual norm, force scale, motion, and whether converged with this error of the
    !> iterate (estimated_error): the residual below tol_force times the force scale and
    !> the error below tol_disp times the motion. The motion is the increment's,
    !> |u - u_n|, scaled up to an increment of the phase's largest size (size_ratio): a
    !> scale that does not vanish as an increment is cut. Measured against its own motion,
    !> an increment cut to 1/500 was held to 500 times the accuracy of a whole one, and
    !> examples/strip_draw stopped with its residual at 1.6e-6 of the force scale and a
    !> correction of 1.6e-7 mm (docs/theory/contact.md, "The convergence test").
    subroutine measure(s, error, norm, scale, moved, converged)
      type(evaluation), intent(in) :: s
      real(wp), intent(in) :: error
      real(wp), intent(out) :: norm, scale, moved
      logical, intent(out) :: converged
      norm = sqrt(dot_product(s%residual, s%residual))
      scale = max(sqrt(sum(s%force**2)), sqrt(sum(s%fint**2, mask=dofs%fixed)), floor)
      moved = max(size_ratio*sqrt(sum((s%u - u_n)**2)), 1.0e-9_wp*element_size)
      converged = norm <= tol_force*scale .and. error <= tol_disp*moved .and. &
                  .not. s%moving
    end subroutine measure

    !> The free dofs of a vector of unknowns into a (3, nnode) field (fixed dofs untouched).
    subroutine scatter(v, field)
      real(wp), intent(in) :: v(nf)
      real(wp), intent(inout) :: field(3, nnode)
      integer :: a, c
      do a = 1, nnode
        do c = 1, 3
          if (dofs%eqn(c, a) >= 0) field(c, a) = v(dofs%eqn(c, a) + 1)
        end do
      end do
    end subroutine scatter

    !> The Newton correction (into delta) for the Jacobian and residual of slot s, and its
    !> size as the line search measures it: ||W M^-1 r||, W the weights and M the factored
    !> matrix (= ||W delta|| when the factors are this Jacobian's). With factors of an
    !> earlier Jacobian and the last GMRES fast, GMRES on W M^-1 J W^-1 to the relative
    !> tolerance forcing; else (or when it does not converge) a factorization.
    subroutine direction(s, forcing, step_size, status)
      type(evaluation), intent(inout) :: s
      real(wp), intent(in) :: forcing
      real(wp), intent(out) :: step_size
      integer, intent(out) :: status
      real(wp), allocatable :: preconditioned(:), perturbed(:)
      integer(int64) :: t0, t1
      integer :: p, i, k
      logical :: gmres_converged, rows_summed
      status = 0
      rows_summed = .false.
      if (newton%reuse .and. factored /= 0 .and. reuse_next /= 0) then
        call krylov(s, have_hint, forcing, newton%krylov_max, preconditioned, &
                    gmres_converged, status)
        if (status < 0) return
        rows_summed = .true.
        if (gmres_converged) then
          step_size = weighted_norm(preconditioned)
          return
        end if
      end if
      call system_clock(t0)
      ! GMRES's sums are the solver's too, but for a symmetric layout's triangle.
      if (.not. rows_summed .or. dofs%symmetric) call sum_entries(s%values, .true.)
      call solver_factorize(solver, size(summed), summed, status)
      if (status == mumps_numerically_singular .and. npair > 0) then
        ! Two closed pairs of one node can hold it along the same direction (a node that
        ! sticks on the die, pushed along its slip by a second tool): its motion is
        ! determined, the split of the load between their multipliers is not, and the
        ! Jacobian is singular. Then the factors of the perturbed Lagrangian (+delta on
        ! the diagonal of dC/dlambda of the pairs with multipliers: a penalty r / delta
        ! behind each law), which split such a load by least squares; a free motion of
        ! the blank stays singular (docs/theory/contact.md, "Redundant pairs").
        perturbed = s%values
        do p = 1, npair
          if (law%on(p) == 0 .or. layout%eliminated(p)) cycle
          do i = 1, 3  ! the (i, i) entry of the pair's 3 x 3 block, the last blocks
            k = layout%contact_values - 9*(npair - p + 1) + 4*i - 3
            perturbed(k) = perturbed(k) + multiplier_perturbation
          end do
        end do
        call sum_entries(perturbed, .true.)
        call solver_factorize(solver, size(summed), summed, status)
      end if
      call system_clock(t1)
      if (status < 0) then
        factored = 0
        return
      end if
      report%factorization_time = report%factorization_time + real(t1 - t0, wp)/real(clock_rate, wp)
      report%factorizations = report%factorizations + 1
      factored = 1
      reuse_next = 1
      if (single) then
        ! The fresh single-precision factors solve only to about eps_single times the
        ! condition number: GMRES on them, to the loop's tolerance or, where the loop
        ! solves exactly, to single_exact_tolerance.
        call krylov(s, .false., merge(forcing, single_exact_tolerance, newton%reuse), &
                    merge(newton%krylov_max, single_exact_iterations, newton%reuse), &
                    preconditioned, gmres_converged, status)
        if (status < 0) return
        ! Factors of this very Jacobian that GMRES cannot bring to the tolerance: its
        ! condition number is near 1/eps_single, and every later correction would be as
        ! poor. The caller goes back to double-precision factors.
        if (.not. gmres_converged) status = status_single_too_coarse
        step_size = weighted_norm(preconditioned)
        return
      end if
      call timed_solve(-s%residual, delta, status)
      if (status < 0) return
      step_size = weighted_norm(delta)
    end subroutine direction

    !> GMRES (into delta) on the present factors for the Jacobian and residual of slot s, to
    !> the relative tolerance in at most ``most`` iterations, from the simplified correction
    !> M^-1 r (into preconditioned: the line search's, s%simplified, where ``hinted``, else
    !> solved here); its time counted as solves, its iterations counted, and whether the
    !> same factors are tried again (reuse_next).
    subroutine krylov(s, hinted, tolerance, most, preconditioned, converged, status)
      type(evaluation), intent(in) :: s
      logical, intent(in) :: hinted
      real(wp), intent(in) :: tolerance
      integer, intent(in) :: most
      real(wp), allocatable, intent(inout) :: preconditioned(:)
      logical, intent(out) :: converged
      integer, intent(out) :: status
      integer(int64) :: t0, t1
      integer :: count
      converged = .false.
      if (.not. allocated(preconditioned)) allocate(preconditioned(n))
      call system_clock(t0)
      if (hinted) then
        preconditioned = s%simplified
      else
        call mumps_solve(-s%residual, preconditioned, status)
        if (status < 0) return
      end if
      call sum_entries(s%values, .false.)
      call gmres(n, rows%row_start, size(rows%col), rows%col, summed, weight, solver, &
                 -s%residual, preconditioned, tolerance, most, delta, count, converged, &
                 status)
      call system_clock(t1)
      report%solve_time = report%solve_time + real(t1 - t0, wp)/real(clock_rate, wp)
      if (status < 0) return
      report%krylov_iterations = report%krylov_iterations + count
      reuse_next = merge(1, 0, count <= newton%krylov_keep)
    end subroutine krylov

    !> summed = the coordinate values summed into the entries of the rows (what GMRES
    !> multiplies with), or, for_solver, into those the solver was analysed with and
    !> factorizes: the same, but a symmetric layout's one triangle (entries). Half as many
    !> as the coordinates on a forming blank, so MUMPS keeps half the copy and arrowheads
    !> (docs/theory/linear-solver.md, "The entries").
    subroutine sum_entries(values, for_solver)
      real(wp), intent(in) :: values(nvalues)
      logical, intent(in) :: for_solver
      if (for_solver .and. dofs%symmetric) then
        call sum_into(values, entries)
      else
        call sum_into(values, rows)
      end if
    end subroutine sum_entries

    !> summed = values summed into the entries of structure.
    subroutine sum_into(values, structure)
      real(wp), intent(in) :: values(nvalues)
      type(row_structure), intent(in) :: structure
      if (allocated(summed)) then
        if (size(summed) /= size(structure%col)) deallocate(summed)
      end if
      if (.not. allocated(summed)) allocate(summed(size(structure%col)))
      call sum_duplicates(nvalues, size(structure%col), values, structure%sources, &
                          structure%source_start, summed)
    end subroutine sum_into

    !> x = M^-1 b with the present factors.
    subroutine mumps_solve(b, x, status)
      real(wp), intent(in) :: b(n)
      real(wp), intent(out) :: x(n)
      integer, intent(out) :: status
      call solver_solve(solver, n, b, x, status)
    end subroutine mumps_solve

    !> mumps_solve, its time counted as solves.
    subroutine timed_solve(b, x, status)
      real(wp), intent(in) :: b(n)
      real(wp), intent(out) :: x(n)
      integer, intent(out) :: status
      integer(int64) :: t0, t1
      call system_clock(t0)
      call mumps_solve(b, x, status)
      call system_clock(t1)
      report%solve_time = report%solve_time + real(t1 - t0, wp)/real(clock_rate, wp)
    end subroutine timed_solve

    !> ||W v||.
    real(wp) function weighted_norm(v)
      real(wp), intent(in) :: v(n)
      weighted_norm = sqrt(sum((weight*v)**2))
    end function weighted_norm

    !> Whether the iterate s, converged with pairs held on their patches, stands against
    !> the search (into slot check): no node-to-surface pair that is in contact, or inside
    !> a tool, farther than hold_depth element sizes from where the held patch has it; and
    !> the Gauss points' normal forces, w_i p_i (p_i = max(0, p_n,i - eps g_i)), changed by
    !> less than
    !> the force tolerance allows the residual (their gaps one by one: an averaged pair's
    !> gap mixes its open points' with those that carry its force).
    logical function held_ok(s, check)
      type(evaluation), intent(in) :: s
      type(evaluation), intent(inout) :: check
      integer :: p, i, t, status, element
      real(wp) :: change, held_force, free_force
      check%u = s%u
      check%force = s%force
      check%shift = s%shift
      lock = 0
      call evaluate(check, 0.0_wp, status, element)
      held_ok = status == 0
      do p = 1, npair
        if (.not. held_ok) exit
        if (law%on(p) == 0 .or. averaged(p)) cycle
        if (.not. (ieee_is_finite(check%gap(p)) .and. ieee_is_finite(s%gap(p)))) then
          held_ok = s%state(p) == contact_inactive  ! the search finds it beyond the reach
          cycle
        end if
        if (s%state(p) == contact_inactive .and. .not. check%gap(p) < 0.0_wp) cycle
        held_ok = abs(check%gap(p) - s%gap(p)) <= hold_depth*element_size
      end do
      if (.not. held_ok) return
      change = 0.0_wp
      do t = 1, ntool
        if (tools%tool(t)%discretization == contact_node) cycle
        ! (A Gauss-point tool's points are followed by its slaves' node points.)
        do i = tools%tool(t)%first_point + 1, tools%tool(t)%first_point + tools%tool(t)%npoint
          held_force = tools%face_weight(i)*s%pressure(i)
          free_force = tools%face_weight(i)*check%pressure(i)
          change = change + (held_force - free_force)**2
        end do
      end do
      held_ok = sqrt(change) <= tol_force*scale
    end function held_ok

    !> Holds the pairs in contact on the patches they have at s, and evaluates s so.
    subroutine hold(s)
      type(evaluation), intent(inout) :: s
      integer :: status, element, t
      lock = s%patch
      lock(1:npair) = merge(lock(1:npair), 0, law%on /= 0)
      do t = 1, ntool
        ! A barrier's slave nodes are not held: held, a node is measured against its
        ! patch's tangent plane continued past the patch's edges, which on a curved tool
        ! lies s^2 / 2R off the surface a distance s past the edge, and the barrier's
        ! stiffness made of that a force of 1.6e5 N on one node of the square cup's punch
        ! (docs/theory/contact.md, "The barrier"); the barrier's depth is continuous
        ! across patches, so its nodes need no hold.
        if (.not. has_barrier(tools%tool(t))) cycle
        lock(npair + node_point(tools, pairs, t, pairs%tool_first(t) + 1): &
             npair + node_point(tools, pairs, t, pairs%tool_first(t + 1))) = 0
      end do
      if (.not. any(lock > 0)) return
      held_on_patches = .true.
      hold_count = hold_count + 1
      call evaluate(s, 0.0_wp, status, element)
      if (status /= 0) then
        report%outcome = outcome_element
        report%element_status = status
        report%element = element
        return
      end if
      call record(s)
    end subroutine hold

    !> The pairs' forces the increment starts from: the converged ones, but a barrier
    !> pair's multiplier is its own force, which its node point carries as its traction
    !> (the converged force holds F(x) too, ddpy_forming).
    function start_force() result(force)
      real(wp) :: force(3, npair)
      integer :: t, p
      force = start%force_n
      do t = 1, ntool
        do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
          if (layout%barrier(p)) force(:, p) = law%traction_n(:, node_point(tools, pairs, t, p))
        end do
      end do
    end function start_force

    !> The converged iterate s as the answer: a barrier pair's force is its own and the
    !> lumped force of the Gauss points on it.
    subroutine finish(s)
      type(evaluation), intent(in) :: s
      integer :: p
      report%outcome = outcome_converged
      answer%u = s%u
      answer%force = s%force
      do p = 1, npair
        if (layout%barrier(p)) answer%force(:, p) = s%force(:, p) + s%lumped(:, p)
      end do
      answer%fint = s%fint
      answer%stress = s%stress
      answer%ep = s%ep
      answer%strain = s%strain
      answer%axes = s%axes
      answer%back = s%back
      answer%state = merge(s%state, contact_inactive, law%on /= 0)
      answer%gap = s%gap
      answer%normal = s%normal
      answer%traction = s%traction
      answer%pressure = s%pressure
      answer%shift = s%shift
    end subroutine finish

  end subroutine forming_increment

  !> The error of a Newton iterate, estimated from the length of the step that led to it
  !> (last) and of the step before (before; +inf unless both were whole Newton steps):
  !> while the corrections contract at rho = last / before < 1/2, those still to come sum
  !> to at most about rho / (1 - rho) last; else last itself, the plain test. So an
  !> iterate one whole step past a contracting one is judged by what remains, not by the
  !> step already taken (docs/theory/contact.md, "The convergence test").
  pure real(wp) function estimated_error(last, before)
    real(wp), intent(in) :: last, before
    real(wp) :: rho
    estimated_error = last
    if (.not. (before > 0.0_wp .and. before < huge(before))) return
    rho = last/before
    if (rho < 0.5_wp) estimated_error = last*rho/(1.0_wp - rho)
  end function estimated_error

  !> The equations of the force-controlled tools (see forming_increment) from the pairs'
  !> forces (lambda; F(x) for an eliminated Gauss-point pair, lambda + lumped = lambda +
  !> F(x) for a barrier pair) and their dC/dt (forming_contact; barrier_dt: a barrier
  !> pair's own law's): each tool's residual sum a . force - F (into hold_residual, F its
  !> hold_force), and from slot hold_base + 1 of values its column per pair (a . dC/dt in
  !> a Gauss-point pair's free equilibrium rows, then in the law rows of a pair with a
  !> multiplier), its row (the holds' coef times the value at slot source, 0-based, or
  !> coef alone where source < 0) and its diagonal -sum a . dC/dt a over its Gauss-point
  !> pairs, whose force F moves with the tool; and its stiffness along its axis, the sum
  !> of the column's |entries| over its pairs that take part (on).
  subroutine hold_equations(dofs, pairs, on, holds, hold_force, eliminated, barrier, force, &
                            lumped, dc_dt, barrier_dt, hold_base, hold_residual, values, &
                            stiffness)
    type(blank_dofs), intent(in) :: dofs
    type(pair_set), intent(in) :: pairs
    integer, intent(in) :: on(pairs%npair), hold_base
    type(force_holds), intent(in) :: holds
    real(wp), intent(in) :: hold_force(holds%nhold), force(3, pairs%npair), &
                            lumped(3, pairs%npair), dc_dt(3, 3, pairs%npair), &
                            barrier_dt(3, 3, pairs%npair)
    logical, intent(in) :: eliminated(pairs%npair), barrier(pairs%npair)
    real(wp), intent(inout) :: hold_residual(holds%nhold), values(*)
    real(wp), intent(out) :: stiffness(holds%nhold)
    real(wp) :: along(3), own(3), a(3), diagonal
    integer :: k, p, i, m, slot, t
    logical :: lumping
    slot = hold_base
    do k = 1, holds%nhold
      t = holds%tool(k)
      a = holds%axis(:, k)
      diagonal = 0.0_wp
      stiffness(k) = 0.0_wp
      hold_residual(k) = -hold_force(k)
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        lumping = eliminated(p) .or. barrier(p)
        hold_residual(k) = hold_residual(k) + dot_product(a, force(:, p))
        if (barrier(p)) hold_residual(k) = hold_residual(k) + dot_product(a, lumped(:, p))
        along = matmul(dc_dt(:, :, p), a)
        own = along
        if (barrier(p)) own = matmul(barrier_dt(:, :, p), a)
        if (on(p) /= 0) then
          if (lumping) stiffness(k) = stiffness(k) + sum(abs(along))
          if (.not. eliminated(p)) stiffness(k) = stiffness(k) + sum(abs(own))
        end if
        if (lumping) then
          do i = 1, 3
            if (dofs%eqn(i, pairs%node(p) + 1) < 0) cycle
            slot = slot + 1
            values(slot) = along(i)
          end do
          diagonal = diagonal - dot_product(a, along)
        end if
        if (eliminated(p)) cycle
        do i = 1, 3
          slot = slot + 1
          values(slot) = own(i)
        end do
      end do
      do m = holds%first(k) + 1, holds%first(k + 1)
        slot = slot + 1
        if (holds%source(m) >= 0) then
          values(slot) = holds%coef(m)*values(holds%source(m) + 1)
        else
          values(slot) = holds%coef(m)
        end if
      end do
      slot = slot + 1
      values(slot) = diagonal
    end do
  end subroutine hold_equations

  !> Longest fraction (at most 1) of the step du (3, nnode) that leaves no free pair's node
  !> (on, open, with a gap) deeper than room_depth inside its tool, the gaps and normals
  !> linearized at the present iterate; at least min_step. The tangent does not see a tool
  !> where a node is free: on a sheet held by a line of contact nodes the full step bends
  !> the span between them along its soft, plastic mode and pushes free nodes deep into the
  !> punch (docs/theory/contact.md).
  pure function penetration_step(nnode, npair, du, pair_node, on, state, gap, normal, &
                                 room_depth, min_step) result(step)
    integer, intent(in) :: nnode, npair, pair_node(npair), on(npair), state(npair)
    real(wp), intent(in) :: du(3, nnode), gap(npair), normal(3, npair), room_depth, min_step
    real(wp) :: step, closing, room
    integer :: p
    step = huge(1.0_wp)
    do p = 1, npair
      if (on(p) == 0 .or. state(p) /= contact_inactive) cycle
      if (.not. ieee_is_finite(gap(p))) cycle
      closing = -dot_product(du(:, pair_node(p) + 1), normal(:, p))
      room = max(gap(p), 0.0_wp) + room_depth
      if (closing > room) step = min(step, room/closing)
    end do
    if (step == huge(1.0_wp)) then
      step = 1.0_wp
    else
      step = max(step, min_step)
    end if
  end function penetration_step

  !> The Newton correction x of J x = f with older factors M (MUMPS's, behind handle):
  !> GMRES from x0 = M^-1 f on J M^-1 (right preconditioning, the preconditioned basis kept
  !> as flexible GMRES keeps it, so the iterate needs no solve of its own), without restart,
  !> at most m steps. J: the entries entry of the rows row_start, columns col (0-based,
  !> see ddpy.core.linalg.row_structure); each product runs over the rows in parallel.
  !>
  !> It stops at the first iterate that meets both of
  !>   ||J x - f|| <= tol ||f||              the residual the Newton loop measures, and
  !>   ||W M^-1 (J x - f)|| <= tol ||W x0||  the correction's error as the factors see it
  !> (W the weights). GMRES minimizes the first; the second is known one solve late (M^-1
  !> of the residual's newest basis vector is the next step's solve), and is waived at the
  !> m-th step. Either alone costs Newton iterations (docs/theory/linear-solver.md,
  !> "GMRES: two measures of one correction"): the second alone (left preconditioning)
  !> leaves force in the stiff contact directions, which M^-1 shrinks; the first alone leaves the sheet's soft bending modes
  !> far off, which small forces move. Returns the iterate x (the last one, when it did not
  !> converge), its steps k, whether it converged (the force residual met, at least) and
  !> status < 0 when a MUMPS solve failed.
  !> Arnoldi with modified Gram-Schmidt run twice (the basis stays orthogonal to rounding
  !> when the operator is far from normal) and Givens rotations for the residual norm.
  subroutine gmres(n, row_start, ncsr, col, entry, weight, handle, f, x0, tol, m, x, k, &
                   converged, status)
    integer, intent(in) :: n, ncsr, row_start(n + 1), col(ncsr), handle, m
    real(wp), intent(in) :: entry(ncsr), weight(n), f(n), x0(n), tol
    real(wp), intent(out) :: x(n)
    integer, intent(out) :: k, status
    logical, intent(out) :: converged
    real(wp), allocatable :: basis(:, :), preconditioned(:, :), w(:)
    ! hessenberg: rotated to the triangle; arnoldi: as Arnoldi left it
    real(wp) :: hessenberg(m + 1, m), arnoldi(m + 1, m), cosines(m), sines(m), res(m + 1), &
                h(m + 1), y(m), beta, a, c, radius, force_target, correction_target
    integer :: i, j, pass, accepted, steps
    logical :: breakdown, force_met(0:m)
    status = 0
    x = x0
    k = 0
    converged = .true.
    if (.not. any(f /= 0.0_wp)) return
    allocate(basis(n, m + 1), preconditioned(n, m + 1), w(n))
    force_target = tol*sqrt(dot_product(f, f))
    correction_target = tol*sqrt(sum((weight*x0)**2))
    call row_product(n, ncsr, row_start, col, entry, x0, w)
    w = f - w
    beta = sqrt(dot_product(w, w))
    hessenberg = 0.0_wp
    arnoldi = 0.0_wp
    cosines = 0.0_wp
    sines = 0.0_wp
    res = 0.0_wp
    res(1) = beta
    force_met = .false.
    force_met(0) = beta <= force_target
    accepted = -1
    steps = 0
    if (beta > 0.0_wp) basis(:, 1) = w/beta
    j = 0
    do while (j <= m .and. beta > 0.0_wp)
      j = j + 1
      if (j > m .and. .not. force_met(m)) exit
      call solver_solve(handle, n, basis(:, j), preconditioned(:, j), status)
      if (status < 0) return
      if (force_met(j - 1)) then  ! the last iterate's correction error, M^-1 of its residual
        if (.not. solved(j - 1)) exit
        h(1:j) = 0.0_wp
        h(1) = beta
        do i = 1, j - 1
          h(1:j) = h(1:j) - y(i)*arnoldi(1:j, i)
        end do
        w = matmul(preconditioned(:, 1:j), h(1:j))
        if (sqrt(sum((weight*w)**2)) <= correction_target) then
          accepted = j - 1
          exit
        end if
      end if
      if (j > m) then  ! the m-th step meets the force residual: taken
        accepted = m
        exit
      end if
      ! w = J M^-1 basis_j
      call row_product(n, ncsr, row_start, col, entry, preconditioned(:, j), w)
      do pass = 1, 2
        do i = 1, j
          h(i) = dot_product(basis(:, i), w)
        end do
        do i = 1, j
          w = w - h(i)*basis(:, i)
        end do
        hessenberg(1:j, j) = hessenberg(1:j, j) + h(1:j)
      end do
      hessenberg(j + 1, j) = sqrt(dot_product(w, w))
      arnoldi(1:j + 1, j) = hessenberg(1:j + 1, j)
      breakdown = .not. hessenberg(j + 1, j) > 1.0e-14_wp*maxval(abs(hessenberg(1:j, j)))
      if (.not. breakdown) basis(:, j + 1) = w/hessenberg(j + 1, j)
      do i = 1, j - 1  ! the earlier rotations on the new column
        a = hessenberg(i, j)
        c = hessenberg(i + 1, j)
        hessenberg(i, j) = cosines(i)*a + sines(i)*c
        hessenberg(i + 1, j) = -sines(i)*a + cosines(i)*c
      end do
      a = hessenberg(j, j)
      c = hessenberg(j + 1, j)
      radius = hypot(a, c)
      if (radius > 0.0_wp) then
        cosines(j) = a/radius
        sines(j) = c/radius
      else
        cosines(j) = 1.0_wp
        sines(j) = 0.0_wp
      end if
      hessenberg(j, j) = radius
      hessenberg(j + 1, j) = 0.0_wp
      res(j + 1) = -sines(j)*res(j)
      res(j) = cosines(j)*res(j)
      force_met(j) = abs(res(j + 1)) <= force_target
      steps = j
      if (breakdown .or. radius == 0.0_wp) then  ! the Krylov space stops growing
        if (force_met(j)) accepted = j
        exit
      end if
    end do
    if (beta == 0.0_wp) accepted = 0
    converged = accepted >= 0
    k = merge(accepted, steps, converged)  ! else the last iterate, for what it is worth
    if (k == 0) return
    if (.not. solved(k)) then
      converged = .false.
      return
    end if
    x = x0 + matmul(preconditioned(:, 1:k), y(1:k))
  contains
    !> y(1:kk), the least-squares coefficients of the kk-step iterate (back substitution on
    !> the rotated triangle); false where it is singular on the Krylov space.
    logical function solved(kk)
      integer, intent(in) :: kk
      integer :: ii
      solved = all([(hessenberg(ii, ii) /= 0.0_wp, ii = 1, kk)])
      if (.not. solved) return
      do ii = kk, 1, -1
        y(ii) = (res(ii) - dot_product(hessenberg(ii, ii + 1:kk), y(ii + 1:kk)))/hessenberg(ii, ii)
      end do
    end function solved
  end subroutine gmres

  !> y = A x for the matrix of rows row_start, columns col (0-based) and entries entry.
  subroutine row_product(n, ncsr, row_start, col, entry, x, y)
    integer, intent(in) :: n, ncsr, row_start(n + 1), col(ncsr)
    real(wp), intent(in) :: entry(ncsr), x(n)
    real(wp), intent(out) :: y(n)
    integer :: i, k
    real(wp) :: total
    !$omp parallel do schedule(static) private(k, total) if(n > 4096)
    do i = 1, n
      total = 0.0_wp
      do k = row_start(i) + 1, row_start(i + 1)
        total = total + entry(k)*x(col(k) + 1)
      end do
      y(i) = total
    end do
    !$omp end parallel do
  end subroutine row_product

end module ddpy_forming_newton
