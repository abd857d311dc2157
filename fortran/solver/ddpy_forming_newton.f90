!> The Newton loop of one increment: the blank's displacements and the contact forces of
!> every (tool, slave) pair solved together, DD3IMP's single loop (docs/theory/contact.md);
!> with no tools, the static problem of a solid under prescribed displacements and loads. Each evaluation assembles the blank (ddpy_solid_assembly) and
!> the contact of every tool (ddpy_forming); each correction is solved with MUMPS, or by
!> GMRES on older factors while they serve; the step is limited where free nodes would
!> enter a tool and globalized by Deuflhard's natural monotonicity test.
!>
!> Unknowns: the free displacement dofs (eqn), then 3 force components per pair. Weights
!> make them all lengths: 1 for displacements, 1 / r for the forces.
module ddpy_forming_newton
  use, intrinsic :: iso_fortran_env, only: int64
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count, yield_landing, material_kinematic
  use ddpy_solid_assembly, only: solid_assemble, shell_modes
  use ddpy_forming, only: forming_contact, tool_fields, surface_gauss, f_surface, f_order, &
                          f_point
  use ddpy_contact, only: contact_inactive
  use ddpy_linear_solver, only: solver_factorize, solver_solve
  use ddpy_sparse, only: sum_duplicates
  implicit none
  private
  public :: forming_increment, newton_settings, newton_integer_settings, outcome_converged, &
            outcome_landing, outcome_element, outcome_not_finite, outcome_solver, &
            outcome_stalled, outcome_hold, penetration_step, gmres, hold_equations

  !> Entries of the real settings: force and displacement tolerances, the yield landing
  !> tolerance (< 0: off), the penetration limit (element sizes) and the shortest step it
  !> may leave, the bounds of the Krylov tolerance, the force scale's floor, the whole-step
  !> ratio (a whole step that fails the monotonicity test is taken where pairs changed
  !> state in it and its residual norm is at most this times the last; <= 0: off), and the
  !> size ratio: the largest increment of the phase over this one's size (>= 1), by which
  !> the convergence test scales the increment's motion up (measure).
  integer, parameter :: newton_settings = 10
  !> Entries of the integer settings: iterations, GMRES iterations at most, GMRES
  !> iterations after which the next correction factorizes, reuse of older factors (0/1),
  !> the MUMPS handle, a guess given (0/1), the touching predictor's resting flag, the
  !> Jacobian stored as its lower triangle (0/1: a symmetric MUMPS instance), the line
  !> search (search_*).
  integer, parameter :: newton_integer_settings = 9
  !> Line searches: none (every step whole, halved only where an element fails);
  !> Deuflhard's natural monotonicity test with the residual-norm fallback (the forming
  !> problem's: the contact law has no potential); the energy line search, a secant on
  !> s(alpha) = du . r(u + alpha du) (a problem with a potential and a symmetric tangent).
  integer, parameter, public :: search_none = 0, search_monotonicity = 1, search_energy = 2
  !> Pairs are held on their patches after 1/hold_fraction of the iterations
  !> (forming_increment); the answer's gaps may then differ from the search's by
  !> hold_depth element sizes. An answer the search refuses is held again on the search's
  !> patches, at most hold_limit times in an increment.
  integer, parameter :: hold_fraction = 3, hold_limit = 3
  real(wp), parameter :: hold_depth = 1.0e-4_wp
  !> A force-controlled tool with no contact stiffness along its axis is moved onto its
  !> nearest slave, touch_depth element sizes into it, at most hold_retouches times in an
  !> increment (forming_increment).
  integer, parameter :: hold_retouches = 3
  real(wp), parameter :: touch_depth = 1.0e-3_wp
  !> What forming_increment returns.
  integer, parameter :: outcome_converged = 0, outcome_landing = 1, outcome_element = 2, &
                        outcome_not_finite = 3, outcome_solver = 4, outcome_stalled = 5, &
                        outcome_hold = 6

contains

  !> Newton iterations of one increment from the converged state (u_n, force_n, the solid
  !> state *_old of a mesh of elements of the given kind, see solid_assemble) to the tools at positions and the fixed dofs at prescribed (forming holds
  !> them at u_n). A prescribed motion not yet reached enters each evaluation through the
  !> tangent, K_fp dp added to the free rows, and each step takes it whole (scaled by the
  !> step length like the rest): the linearized predictor, not a jump of the boundary
  !> nodes, which would invert the elements next to them. See the arguments of
  !> forming_contact for the tools and pairs (and the Gauss points' tangential tractions
  !> traction_n and pressure multipliers pressure_n of Gauss-point contact). Returns
  !> outcome with, as it says: u, force, the solid state, the internal forces fint, the
  !> contact states (inactive where off), gaps, normals and the Gauss points' tractions and
  !> pressures when converged; the landing
  !> fraction in detail(1); the element status and element in info(1:2); the MUMPS code in
  !> info(3); the last relative residual and correction in detail(1:2) and the pairs that
  !> changed state in the last iteration in info(4) when stalled. history(1:4, 1:niter):
  !> every iteration's residual norm, (relative residual, relative correction) and the
  !> length of the step that led to it (0 for the start). counters: evaluations,
  !> corrections, factorizations, Krylov iterations, line searches that ended on the
  !> residual-norm fallback;
  !> timings (s): assembly, contact, factorization, solve. factored, reuse_next: the
  !> solver's factors are this layout's, the last GMRES converged fast.
  !> The solid-shell's enhanced parameters live in the evaluations like the trial state:
  !> each evaluation starts its local iteration from those of the iterate the step leaves
  !> (zero at the start of the increment), so an evaluation is a function of the iterate
  !> and its start, not of the line search's earlier trials. back_old, back (6, 8, nback):
  !> the backstress of mixed hardening, carried like the stress (nback = ne; without
  !> kinematic hardening not read, and back = back_old).
  !>
  !> Force-controlled tools (nhold of them, docs/theory/contact.md): tool hold_tool(k) sits
  !> at positions + shift(k) hold_axis(:, k), shift(k) one more unknown (after the pairs'
  !> forces), whose equation is sum over the tool's pairs of hold_axis . lambda =
  !> hold_target(k), the force the tool presses on the blank with. Its Jacobian entries
  !> follow the contact blocks: per tool, its column (the rows of its pairs' laws, or a
  !> Gauss-point pair's free equilibrium rows), its row (hold_first(k) + 1 ..
  !> hold_first(k + 1): hold_coef times the value at slot hold_source (0-based), or
  !> hold_coef alone where hold_source < 0), its diagonal. A step moves a tool by at most
  !> hold_step; outcome_hold when a tool has no contact stiffness along its axis (info(2)
  !> 1) or has moved farther than reach in the increment (info(2) 2), info(1) the tool.
  subroutine forming_increment(nnode, x0, ne, conn, kind, props, u_ref, axes_old, stress_old, &
                               ep_old, strain_old, nback, back_old, eqn, offsets, fixed, nf, &
                               k_slots, &
                               n_coupling, nvalues, row_start, ncsr, col, sources, &
                               source_start, ntool, table, tol, coef, &
                               degrees, triangle, tree_lower, tree_upper, tree_child, frame, &
                               frame_lower, frame_upper, grid_start, grid_params, &
                               grid_normals, grid_points, facing, face_first, nface, faces, &
                               corner, npoint, face_weight, penalty, positions, positions_n, &
                               reach, size, touching, npair, tool_first, pair_node, npatch, &
                               patch_first, patch_node, on, r, mu, held, traction_n, &
                               pressure_n, u_n, &
                               force_n, external, prescribed, guess, settings, isettings, &
                               factored, reuse_next, u, force, fint, stress, ep, strain, axes, &
                               back, state, gap, normal, traction, pressure, niter, history, &
                               counters, &
                               timings, outcome, info, detail, nhold, hold_tool, hold_axis, &
                               hold_target, hold_first, nhold_src, hold_source, hold_coef, &
                               hold_step, shift)
    integer, intent(in) :: nnode, ne, kind, nf, k_slots, n_coupling, nvalues, ncsr, ntool, &
                           nface, npoint, npair, npatch, nback, nhold, nhold_src
    integer, intent(in) :: conn(8, ne), eqn(3, nnode), offsets(ne + 1), fixed(3, nnode), &
                           row_start(nf + 3*npair + nhold + 1), col(ncsr), sources(*), &
                           source_start(ncsr + 1), table(tool_fields, ntool), &
                           degrees(*), triangle(*), tree_child(*), grid_start(*), &
                           face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                           tool_first(ntool + 1), pair_node(npair), on(npair), &
                           patch_first(npair + 1), patch_node(npatch), &
                           held(3, npair), isettings(newton_integer_settings)
    real(wp), intent(in) :: x0(3, nnode), props(material_prop_count), u_ref(3, nnode), &
                            axes_old(3, 3, 8, ne), stress_old(6, 8, ne), ep_old(8, ne), &
                            strain_old(6, 8, ne), back_old(6, 8, nback), tol(ntool), &
                            coef(*), tree_lower(*), &
                            tree_upper(*), frame(*), frame_lower(*), frame_upper(*), &
                            grid_params(*), grid_normals(*), grid_points(*), &
                            facing(3, ntool), positions(3, ntool), positions_n(3, ntool), &
                            face_weight(npoint), penalty(5, ntool), &
                            traction_n(3, npoint), pressure_n(npoint), reach, size, &
                            touching, r(npair), &
                            mu(npair), u_n(3, nnode), &
                            force_n(3, npair), external(3, nnode), prescribed(3, nnode), &
                            guess(3, nnode), settings(newton_settings)
    integer, intent(inout) :: factored, reuse_next
    real(wp), intent(out) :: u(3, nnode), force(3, npair), fint(3, nnode), &
                             stress(6, 8, ne), ep(8, ne), &
                             strain(6, 8, ne), axes(3, 3, 8, ne), back(6, 8, nback), &
                             gap(npair), normal(3, npair), traction(3, npoint), &
                             pressure(npoint), history(4, *), &
                             timings(4), detail(2)
    integer, intent(out) :: state(npair), niter, counters(5), outcome, info(4)
    integer, intent(in) :: hold_tool(nhold), hold_first(nhold + 1), hold_source(nhold_src)
    real(wp), intent(in) :: hold_axis(3, nhold), hold_target(nhold), hold_coef(nhold_src), &
                            hold_step
    real(wp), intent(out) :: shift(nhold)

    !> One evaluation: the iterate and what was evaluated there.
    type :: evaluation
      real(wp), allocatable :: u(:, :), force(:, :), residual(:), values(:), fint(:, :), &
                               stress(:, :, :), ep(:, :), strain(:, :, :), axes(:, :, :, :), &
                               back(:, :, :), alpha(:, :), gap(:), normal(:, :), simplified(:), &
                               traction(:, :), pressure(:), shift(:), dc_dt(:, :, :), &
                               stiffness(:)
      integer, allocatable :: state(:), patch(:)
      logical :: moving  ! some fixed dof short of its prescribed value
      real(wp) :: rest   ! how far short: the norm over the fixed dofs
    end type evaluation
    type(evaluation) :: slot(2)
    real(wp), allocatable :: weight(:), delta(:), du(:, :), dforce(:, :), x_n(:, :), &
                             kdu(:, :), dp(:, :), u_cur(:, :), force_cur(:, :), &
                             alpha_cur(:, :), shift_cur(:), dshift(:)
    integer, allocatable :: previous(:), lock(:)
    logical, allocatable :: eliminated(:), averaged(:)
    real(wp), allocatable :: coupling(:)
    integer :: tool, pair, comp, entry, k, hold_base, retouches
    logical :: retouched
    real(wp) :: tol_force, tol_disp, yield_tol, floor, norm, scale, moved, correction, rel, &
                forcing, alpha, step_size, du_norm, landing, t_norm, t_scale, t_moved, &
                alpha_fallback, whole_step, size_ratio
    integer :: max_iterations, cur, trial, fallback, buffer, iteration, ls, n, status, &
               element, handle, last_status, last_element, hold_after, holds
    logical :: converged, have_previous, have_hint, accepted, t_converged, symmetric, &
               moving, held_on_patches
    integer :: search
    integer(int64) :: clock_rate

    call system_clock(count_rate=clock_rate)
    tol_force = settings(1)
    tol_disp = settings(2)
    yield_tol = settings(3)
    floor = settings(8)
    whole_step = settings(9)
    size_ratio = max(settings(10), 1.0_wp)
    max_iterations = isettings(1)
    hold_after = max(2, max_iterations/hold_fraction)
    handle = isettings(5)
    symmetric = isettings(8) /= 0
    search = isettings(9)
    n = nf + 3*npair + nhold
    retouches = 0
    counters = 0
    shift = 0.0_wp
    timings = 0.0_wp
    info = 0
    detail = 0.0_wp
    niter = 0
    outcome = outcome_stalled
    allocate(weight(n), delta(n), du(3, nnode), dforce(3, npair), x_n(3, nnode), &
             kdu(3, nnode), dp(3, nnode), previous(npair), u_cur(3, nnode), &
             force_cur(3, npair), alpha_cur(shell_modes, ne), lock(npair + npoint), &
             shift_cur(nhold), dshift(nhold))
    alpha_cur = 0.0_wp
    lock = 0
    held_on_patches = .false.
    holds = 0
    dp = 0.0_wp
    step_size = 0.0_wp
    weight(1:nf) = 1.0_wp
    weight(nf + 1:nf + 3*npair) = reshape(spread(1.0_wp/r, 1, 3), [3*npair])
    weight(nf + 3*npair + 1:) = 1.0_wp  ! the tools' shifts are lengths
    ! The pairs of Gauss-point tools, whose multipliers are eliminated (forming_contact):
    ! their coupling entries (node's equilibrium row, multiplier) are 0, the others' -1.
    allocate(eliminated(npair), averaged(npair), coupling(n_coupling))
    do tool = 1, ntool
      eliminated(tool_first(tool) + 1:tool_first(tool + 1)) = &
        table(f_surface, tool) == surface_gauss
      ! Pairs whose gap averages Gauss points' (held_ok checks the points instead).
      averaged(tool_first(tool) + 1:tool_first(tool + 1)) = table(f_surface, tool) /= 0
    end do
    entry = 0
    do pair = 1, npair
      do comp = 1, 3
        if (eqn(comp, pair_node(pair) + 1) < 0) cycle
        entry = entry + 1
        coupling(entry) = merge(0.0_wp, -1.0_wp, eliminated(pair))
      end do
    end do
    ! The force-controlled tools' entries close the values: per tool its column, its row
    ! and its diagonal.
    hold_base = nvalues
    do k = 1, nhold
      tool = hold_tool(k)
      do pair = tool_first(tool) + 1, tool_first(tool + 1)
        if (eliminated(pair)) then
          hold_base = hold_base - count(eqn(:, pair_node(pair) + 1) >= 0)
        else
          hold_base = hold_base - 3
        end if
      end do
      hold_base = hold_base - (hold_first(k + 1) - hold_first(k)) - 1
    end do
    x_n = x0 + u_n
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
               slot(cur)%dc_dt(3, 3, npair), slot(cur)%stiffness(nhold))
      slot(cur)%back = back_old
      slot(cur)%values(k_slots + 1:k_slots + n_coupling) = coupling
      slot(cur)%shift = 0.0_wp
    end do
    correction = ieee_value(1.0_wp, ieee_positive_inf)
    alpha = 0.0_wp
    have_hint = .false.
    have_previous = .false.
    ! The extrapolated start, unless an element fails there; else the converged state.
    cur = 1
    status = 1
    if (isettings(6) /= 0) then
      slot(cur)%u = guess
      slot(cur)%force = force_n
      call evaluate(slot(cur), touching, status, element)
    end if
    if (status /= 0) then
      slot(cur)%u = u_n
      slot(cur)%force = force_n
      call evaluate(slot(cur), touching, status, element)
      if (status /= 0) then
        outcome = outcome_element
        info(1:2) = [status, element]
        return
      end if
    end if
    do iteration = 0, max_iterations
      niter = niter + 1
      call record(slot(cur))
      history(4, niter) = alpha
      if (.not. ieee_is_finite(norm)) then
        outcome = outcome_not_finite
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
          if (.not. converged .and. holds < hold_limit .and. iteration < max_iterations) then
            call hold(slot(cur))
            if (outcome == outcome_element) return
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
        if (outcome == outcome_element) return
      end if
      if (iteration == max_iterations) then
        outcome = outcome_stalled
        detail = [norm/scale, correction/moved]
        info(4) = -1
        if (have_previous) info(4) = count(on /= 0 .and. slot(cur)%state /= previous)
        return
      end if
      ! Inexact Newton (Eisenstat and Walker): the correction's relative error may be a
      ! tenth of the relative residual (the rate stays quadratic), or as large as leaves
      ! the next residual a tenth of the tolerance (the last iteration).
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
          if (outcome == outcome_element) return
        end if
        outcome = outcome_hold
        info(1:2) = [hold_tool(k), 1]
        return
      end do
      if (retouched) then
        retouches = retouches + 1
        alpha = 0.0_wp
        cycle
      end if
      rel = norm/scale
      forcing = min(settings(6), max(settings(7), 0.1_wp*rel, &
                                     0.1_wp*tol_force/max(rel, 1.0e-300_wp)))
      counters(2) = counters(2) + 1
      call direction(slot(cur), forcing, step_size, status)
      if (status < 0) then
        outcome = outcome_solver
        info(3) = status
        return
      end if
      du = 0.0_wp
      call scatter(delta(1:nf), du)
      if (slot(cur)%moving) then
        ! The prescribed rest is part of the step (its constraint rows are solved exactly),
        ! and of the step's length that the line search compares against.
        where (fixed /= 0) du = prescribed - slot(cur)%u
        step_size = hypot(step_size, slot(cur)%rest)
      end if
      dforce = reshape(delta(nf + 1:nf + 3*npair), [3, npair])
      dshift = delta(nf + 3*npair + 1:)
      du_norm = sqrt(dot_product(delta(1:nf), delta(1:nf)) + dot_product(dshift, dshift))
      ! The factors hold this iteration's Jacobian from here. The first trial stops short
      ! where the step would push a free node into a tool.
      alpha = penetration_step(nnode, npair, du, pair_node, on, slot(cur)%state, &
                               slot(cur)%gap, slot(cur)%normal, settings(4)*size, &
                               settings(5))
      if (nhold > 0) then
        ! A force-controlled tool moves at most hold_step in a step.
        if (maxval(abs(dshift))*alpha > hold_step) alpha = hold_step/maxval(abs(dshift))
      end if
      alpha = min(alpha, barrier_step(nnode, ntool, npair, du, tool_first, pair_node, on, &
                                      slot(cur)%gap, slot(cur)%normal, penalty, nhold, &
                                      hold_tool, hold_axis, dshift, settings(5)))
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
            call measure(slot(trial), du_norm, t_norm, t_scale, t_moved, t_converged)
            if (t_converged) then  ! converged: the next iteration returns it
              accepted = .true.
              exit
            end if
          end if
          ! Natural monotonicity test (Deuflhard): the simplified Newton correction at
          ! the trial, with this iteration's factors, must be shorter than the step's.
          call timed_solve(-slot(trial)%residual, slot(trial)%simplified, status)
          if (status < 0) then
            outcome = outcome_solver
            info(3) = status
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
            if (any(on /= 0 .and. slot(trial)%state /= slot(cur)%state)) then
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
          counters(5) = counters(5) + 1
        else
          alpha = 2.0_wp*alpha
        end if
        have_hint = .true.
      end if
      if (last_status /= 0) then
        outcome = outcome_element
        info(1:2) = [last_status, last_element]
        return
      end if
      cur = trial
      correction = alpha*du_norm
      do k = 1, nhold
        if (abs(slot(cur)%shift(k)) > reach) then
          outcome = outcome_hold
          info(1:2) = [hold_tool(k), 2]
          return
        end if
      end do
      if (yield_tol >= 0.0_wp .and. alpha == 1.0_wp) then
        ! The elastic predictor is the first full Newton step: a step shortened by the
        ! line search or the penetration limit starts from a poor iterate, whose strains
        ! say little of where the converged path yields.
        if (material_kinematic(props) .and. nback == ne) then
          ! The elastic path of the relative stress: the backstress stays while elastic.
          landing = yield_landing(props, 8*ne, stress_old - back_old, ep_old, &
                                  slot(cur)%strain - strain_old, yield_tol)
        else
          landing = yield_landing(props, 8*ne, stress_old, ep_old, &
                                  slot(cur)%strain - strain_old, yield_tol)
        end if
        yield_tol = -1.0_wp
        if (landing < 1.0_wp) then
          outcome = outcome_landing
          detail(1) = landing
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
        where (fixed /= 0) s%u = prescribed
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
      counters(1) = counters(1) + 1
      call system_clock(t0)
      where (fixed /= 0)
        dp = prescribed - s%u
      elsewhere
        dp = 0.0_wp
      end where
      s%moving = any(dp /= 0.0_wp)
      s%rest = 0.0_wp
      if (s%moving) s%rest = sqrt(sum(dp**2))
      call solid_assemble(nnode, x0, ne, conn, kind, u_ref, s%u, props, axes_old, &
                          stress_old, ep_old, strain_old, nback, back_old, alpha_cur, eqn, &
                          symmetric, .true., offsets, k_slots, s%values(1:k_slots), s%moving, &
                          dp, s%fint, kdu, s%stress, s%ep, s%strain, s%axes, s%back, s%alpha, &
                          status, element)
      call system_clock(t1)
      timings(1) = timings(1) + real(t1 - t0, wp)/real(clock_rate, wp)
      if (status /= 0) return
      do a = 1, nnode
        do c = 1, 3
          if (eqn(c, a) >= 0) s%residual(eqn(c, a) + 1) = s%fint(c, a) - external(c, a)
        end do
      end do
      if (s%moving) then  ! the linearized rest of the prescribed motion
        do a = 1, nnode
          do c = 1, 3
            if (eqn(c, a) >= 0) s%residual(eqn(c, a) + 1) = s%residual(eqn(c, a) + 1) + &
                                                            kdu(c, a)
          end do
        end do
      end if
      placed = positions
      do k = 1, nhold
        placed(:, hold_tool(k)) = placed(:, hold_tool(k)) + s%shift(k)*hold_axis(:, k)
      end do
      call forming_contact(nnode, x0 + s%u, x_n, fixed, ntool, table, tol, coef, degrees, &
                           triangle, tree_lower, tree_upper, tree_child, frame, frame_lower, &
                           frame_upper, grid_start, grid_params, grid_normals, grid_points, &
                           facing, face_first, nface, faces, corner, npoint, face_weight, &
                           penalty, placed, positions_n, reach, size, touching_gap, isettings(7), &
                           npair, tool_first, pair_node, npatch, patch_first, patch_node, on, &
                           s%force, r, mu, held, traction_n, pressure_n, lock, eqn, nf, &
                           k_slots, nvalues, s%residual, s%values, s%state, s%gap, s%normal, &
                           s%traction, s%pressure, s%patch, s%dc_dt)
      ! A Gauss-point pair's multiplier is eliminated: lambda = F(x), C = 0.
      do p = 1, npair
        if (.not. eliminated(p)) cycle
        s%force(:, p) = s%force(:, p) - s%residual(nf + 3*p - 2:nf + 3*p)
        s%residual(nf + 3*p - 2:nf + 3*p) = 0.0_wp
      end do
      call hold_equations(nnode, ntool, npair, tool_first, pair_node, on, eqn, &
                          eliminated, s%force, s%dc_dt, nhold, hold_tool, hold_axis, &
                          hold_target, hold_first, nhold_src, hold_source, hold_coef, &
                          hold_base, s%residual(nf + 3*npair + 1:), s%values, s%stiffness)
      call system_clock(t2)
      timings(2) = timings(2) + real(t2 - t1, wp)/real(clock_rate, wp)
    end subroutine evaluate

    !> Moves force-controlled tool k of slot s along its axis onto its nearest slave (by
    !> the gaps along the tool's normals at the pairs' closest points), touch_depth
    !> element sizes into it, and evaluates s there; false where no slave within the
    !> search's reach faces it or an element fails (outcome then says so).
    logical function retouch(s, k)
      type(evaluation), intent(inout) :: s
      integer, intent(in) :: k
      real(wp) :: closing, travel
      integer :: p, status, element
      retouch = .false.
      travel = huge(1.0_wp)
      do p = tool_first(hold_tool(k)) + 1, tool_first(hold_tool(k) + 1)
        if (on(p) == 0 .or. .not. ieee_is_finite(s%gap(p))) cycle
        closing = dot_product(s%normal(:, p), hold_axis(:, k))
        if (closing > 0.5_wp) travel = min(travel, s%gap(p)/closing)
      end do
      if (travel == huge(1.0_wp)) return
      s%shift(k) = s%shift(k) + travel + touch_depth*size
      call evaluate(s, 0.0_wp, status, element)
      if (status /= 0) then
        outcome = outcome_element
        info(1:2) = [status, element]
        return
      end if
      retouch = .true.
    end function retouch

    !> measure for slot s, as this iteration's history (residual, relative residual and
    !> correction).
    subroutine record(s)
      type(evaluation), intent(in) :: s
      call measure(s, correction, norm, scale, moved, converged)
      history(1, niter) = norm
      history(2, niter) = norm/scale
      history(3, niter) = correction/moved
    end subroutine record

    !> Residual norm, force scale, motion, and whether converged with this correction:
    !> the residual below tol_force times the force scale and the correction below
    !> tol_disp times the motion. The motion is the increment's, |u - u_n|, scaled up to an
    !> increment of the phase's largest size (size_ratio): a scale that does not vanish as
    !> an increment is cut. Measured against its own motion, an increment cut to 1/500
    !> was held to 500 times the accuracy of a whole one, and examples/strip_draw stopped
    !> with its residual at 1.6e-6 of the force scale and a correction of 1.6e-7 mm
    !> (docs/theory/contact.md, "The convergence test").
    subroutine measure(s, correction, norm, scale, moved, converged)
      type(evaluation), intent(in) :: s
      real(wp), intent(in) :: correction
      real(wp), intent(out) :: norm, scale, moved
      logical, intent(out) :: converged
      norm = sqrt(dot_product(s%residual, s%residual))
      scale = max(sqrt(sum(s%force**2)), sqrt(sum(s%fint**2, mask=fixed /= 0)), floor)
      moved = max(size_ratio*sqrt(sum((s%u - u_n)**2)), 1.0e-9_wp*size)
      converged = norm <= tol_force*scale .and. correction <= tol_disp*moved .and. &
                  .not. s%moving
    end subroutine measure

    !> The free dofs of a vector of unknowns into a (3, nnode) field (fixed dofs untouched).
    subroutine scatter(v, field)
      real(wp), intent(in) :: v(nf)
      real(wp), intent(inout) :: field(3, nnode)
      integer :: a, c
      do a = 1, nnode
        do c = 1, 3
          if (eqn(c, a) >= 0) field(c, a) = v(eqn(c, a) + 1)
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
      real(wp), allocatable :: preconditioned(:), z(:)
      integer(int64) :: t0, t1
      integer :: count
      logical :: gmres_converged
      status = 0
      if (isettings(4) /= 0 .and. factored /= 0 .and. reuse_next /= 0) then
        allocate(preconditioned(n), z(n))
        call system_clock(t0)
        if (have_hint) then
          preconditioned = weight*s%simplified
        else
          call mumps_solve(-s%residual, preconditioned, status)
          if (status < 0) return
          preconditioned = weight*preconditioned
        end if
        call gmres(n, nvalues, s%values, row_start, ncsr, col, sources, source_start, &
                   weight, handle, preconditioned, forcing, isettings(2), z, count, &
                   gmres_converged, status)
        call system_clock(t1)
        timings(4) = timings(4) + real(t1 - t0, wp)/real(clock_rate, wp)
        if (status < 0) return
        counters(4) = counters(4) + count
        reuse_next = merge(1, 0, count <= isettings(3))
        if (gmres_converged) then
          delta = z/weight
          step_size = sqrt(dot_product(preconditioned, preconditioned))
          return
        end if
      end if
      call system_clock(t0)
      call solver_factorize(handle, nvalues, s%values, status)
      call system_clock(t1)
      if (status < 0) then
        factored = 0
        return
      end if
      timings(3) = timings(3) + real(t1 - t0, wp)/real(clock_rate, wp)
      counters(3) = counters(3) + 1
      factored = 1
      reuse_next = 1
      call timed_solve(-s%residual, delta, status)
      if (status < 0) return
      step_size = weighted_norm(delta)
    end subroutine direction

    !> x = M^-1 b with the present factors.
    subroutine mumps_solve(b, x, status)
      real(wp), intent(in) :: b(n)
      real(wp), intent(out) :: x(n)
      integer, intent(out) :: status
      call solver_solve(handle, n, b, x, status)
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
      timings(4) = timings(4) + real(t1 - t0, wp)/real(clock_rate, wp)
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
        if (on(p) == 0 .or. averaged(p)) cycle
        if (.not. (ieee_is_finite(check%gap(p)) .and. ieee_is_finite(s%gap(p)))) then
          held_ok = s%state(p) == contact_inactive  ! the search finds it beyond the reach
          cycle
        end if
        if (s%state(p) == contact_inactive .and. .not. check%gap(p) < 0.0_wp) cycle
        held_ok = abs(check%gap(p) - s%gap(p)) <= hold_depth*size
      end do
      if (.not. held_ok) return
      change = 0.0_wp
      do t = 1, ntool
        if (table(f_surface, t) == 0) cycle
        ! (A Gauss-point tool's points are followed by its slaves' barrier points.)
        do i = table(f_point, t) + 1, table(f_point, t) + &
                                      table(f_order, t)**2*(face_first(t + 1) - face_first(t)) &
                                      + merge(tool_first(t + 1) - tool_first(t), 0, &
                                              table(f_surface, t) == surface_gauss)
          held_force = face_weight(i)*s%pressure(i)
          free_force = face_weight(i)*check%pressure(i)
          change = change + (held_force - free_force)**2
        end do
      end do
      held_ok = sqrt(change) <= tol_force*scale
    end function held_ok

    !> Holds the pairs in contact on the patches they have at s, and evaluates s so.
    subroutine hold(s)
      type(evaluation), intent(inout) :: s
      integer :: status, element
      lock = s%patch
      lock(1:npair) = merge(lock(1:npair), 0, on /= 0)
      if (.not. any(lock > 0)) return
      held_on_patches = .true.
      holds = holds + 1
      call evaluate(s, 0.0_wp, status, element)
      if (status /= 0) then
        outcome = outcome_element
        info(1:2) = [status, element]
        return
      end if
      call record(s)
    end subroutine hold

    !> The converged iterate s as the answer.
    subroutine finish(s)
      type(evaluation), intent(in) :: s
      outcome = outcome_converged
      u = s%u
      force = s%force
      fint = s%fint
      stress = s%stress
      ep = s%ep
      strain = s%strain
      axes = s%axes
      back = s%back
      state = merge(s%state, contact_inactive, on /= 0)
      gap = s%gap
      normal = s%normal
      traction = s%traction
      pressure = s%pressure
      shift = s%shift
    end subroutine finish

  end subroutine forming_increment

  !> The equations of the nhold force-controlled tools (see forming_increment) from the
  !> pairs' forces (lambda; F(x) for an eliminated Gauss-point pair) and their dC/dt
  !> (forming_contact): each tool's residual sum a . lambda - F (into hold_residual), and
  !> from slot hold_base + 1 of values its column a . dC/dt per pair (the law rows, or an
  !> eliminated pair's free equilibrium rows), its row (hold_coef times the value at slot
  !> hold_source, 0-based, or hold_coef alone where hold_source < 0) and its diagonal
  !> -sum a . dC/dt a over its eliminated pairs, whose force F = lambda - C moves with the
  !> tool; and its stiffness along its axis, the sum of |dC/dt a| over its pairs that take
  !> part (on).
  subroutine hold_equations(nnode, ntool, npair, tool_first, pair_node, on, eqn, &
                            eliminated, force, dc_dt, nhold, hold_tool, hold_axis, &
                            hold_target, hold_first, nhold_src, hold_source, hold_coef, &
                            hold_base, hold_residual, values, stiffness)
    integer, intent(in) :: nnode, ntool, npair, nhold, nhold_src, hold_base
    integer, intent(in) :: tool_first(ntool + 1), pair_node(npair), on(npair), &
                           eqn(3, nnode), hold_tool(nhold), hold_first(nhold + 1), &
                           hold_source(nhold_src)
    logical, intent(in) :: eliminated(npair)
    real(wp), intent(in) :: force(3, npair), dc_dt(3, 3, npair), hold_axis(3, nhold), &
                            hold_target(nhold), hold_coef(nhold_src)
    real(wp), intent(inout) :: hold_residual(nhold), values(*)
    real(wp), intent(out) :: stiffness(nhold)
    real(wp) :: along(3), a(3), diagonal
    integer :: k, p, i, m, slot, t
    slot = hold_base
    do k = 1, nhold
      t = hold_tool(k)
      a = hold_axis(:, k)
      diagonal = 0.0_wp
      stiffness(k) = 0.0_wp
      hold_residual(k) = -hold_target(k)
      do p = tool_first(t) + 1, tool_first(t + 1)
        hold_residual(k) = hold_residual(k) + dot_product(a, force(:, p))
        along = matmul(dc_dt(:, :, p), a)
        if (on(p) /= 0) stiffness(k) = stiffness(k) + sum(abs(along))
        do i = 1, 3
          if (eliminated(p) .and. eqn(i, pair_node(p) + 1) < 0) cycle
          slot = slot + 1
          values(slot) = along(i)
        end do
        if (eliminated(p)) diagonal = diagonal - dot_product(a, along)
      end do
      do m = hold_first(k) + 1, hold_first(k + 1)
        slot = slot + 1
        if (hold_source(m) >= 0) then
          values(slot) = hold_coef(m)*values(hold_source(m) + 1)
        else
          values(slot) = hold_coef(m)
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

  !> Longest fraction (at most 1) of the step du (3, nnode), with the force-controlled
  !> tools' shifts dshift along hold_axis, that takes no slave node of a tool with a
  !> barrier (penalty(3, t) > 0) from above the end of the barrier's ramp (d_b + w,
  !> penalty(4:5, t)) to below it, the pair's depth (-gap) and normal linearized at the
  !> present iterate; at least min_step. Where a node is not yet in the ramp the tangent
  !> has none of the barrier's stiffness, and the full step (a holder pressed with a force
  !> it meets with the penalty alone, 3 % of the thickness deep) lands it far inside: the
  !> next iterate's barrier force, many times the load, throws the tool off the blank.
  pure function barrier_step(nnode, ntool, npair, du, tool_first, pair_node, on, gap, &
                             normal, penalty, nhold, hold_tool, hold_axis, dshift, &
                             min_step) result(step)
    integer, intent(in) :: nnode, ntool, npair, tool_first(ntool + 1), pair_node(npair), &
                           on(npair), nhold, hold_tool(nhold)
    real(wp), intent(in) :: du(3, nnode), gap(npair), normal(3, npair), penalty(5, ntool), &
                            hold_axis(3, nhold), dshift(nhold), min_step
    real(wp) :: step, tool_du(3), depth, ramp_end, closing
    integer :: t, p, k
    step = 1.0_wp
    do t = 1, ntool
      if (.not. penalty(3, t) > 0.0_wp) cycle
      tool_du = 0.0_wp
      do k = 1, nhold
        if (hold_tool(k) == t) tool_du = tool_du + dshift(k)*hold_axis(:, k)
      end do
      ramp_end = penalty(4, t) + penalty(5, t)
      do p = tool_first(t) + 1, tool_first(t + 1)
        if (on(p) == 0 .or. .not. ieee_is_finite(gap(p))) cycle
        depth = -gap(p)
        if (depth >= ramp_end) cycle
        closing = -dot_product(du(:, pair_node(p) + 1) - tool_du, normal(:, p))
        if (depth + closing*step > ramp_end) step = (ramp_end - depth)/closing
      end do
    end do
    step = max(step, min_step)
  end function barrier_step

  !> GMRES from 0, without restart, on the operator v -> W M^-1 J W^-1 v (J: the
  !> coordinate values summed into the rows of the structure row_start, col, sources,
  !> source_start (0-based, see ddpy.core.linalg.row_structure), once, in parallel; each
  !> product runs over the rows in parallel; M the factors MUMPS holds
  !> behind handle; W the weights): the iterate z, the iterations and whether
  !> ||op(z) - b|| <= tol ||b||; status < 0: a MUMPS solve failed. Arnoldi with modified Gram-Schmidt run twice
  !> (the basis stays orthogonal to rounding when the operator is far from normal) and
  !> Givens rotations for the residual norm.
  subroutine gmres(n, nvalues, values, row_start, ncsr, col, sources, source_start, weight, &
                   handle, b, tol, m, z, k, converged, status)
    integer, intent(in) :: n, nvalues, ncsr, row_start(n + 1), col(ncsr), sources(*), &
                           source_start(ncsr + 1), handle, m
    real(wp), intent(in) :: values(nvalues), weight(n), b(n), tol
    real(wp), intent(out) :: z(n)
    integer, intent(out) :: k, status
    logical, intent(out) :: converged
    real(wp), allocatable :: basis(:, :), w(:), jv(:), entry(:)
    real(wp) :: hessenberg(m + 1, m), cosines(m), sines(m), res(m + 1), h(m + 1), beta, &
                a, c, radius, y(m)
    integer :: i, j, pass, last
    logical :: breakdown
    status = 0
    z = 0.0_wp
    k = 0
    converged = .true.
    beta = sqrt(dot_product(b, b))
    if (beta == 0.0_wp) return
    allocate(basis(n, m + 1), w(n), jv(n), entry(ncsr))
    call sum_duplicates(nvalues, ncsr, values, sources, source_start, entry)
    basis(:, 1) = b/beta
    hessenberg = 0.0_wp
    cosines = 0.0_wp
    sines = 0.0_wp
    res = 0.0_wp
    res(1) = beta
    last = 0
    do j = 1, m
      last = j
      ! w = W M^-1 J W^-1 basis_j
      w = basis(:, j)/weight
      call row_product(n, ncsr, row_start, col, entry, w, jv)
      call solver_solve(handle, n, jv, w, status)
      if (status < 0) return
      w = weight*w
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
      if (abs(res(j + 1)) <= tol*beta .or. breakdown .or. radius == 0.0_wp) exit
    end do
    k = last
    converged = abs(res(k + 1)) <= tol*beta
    do i = 1, k
      if (hessenberg(i, i) == 0.0_wp) then  ! singular on the Krylov space
        converged = .false.
        return
      end if
    end do
    do i = k, 1, -1  ! back substitution on the triangular factor
      y(i) = (res(i) - dot_product(hessenberg(i, i + 1:k), y(i + 1:k)))/hessenberg(i, i)
    end do
    do i = 1, k
      z = z + y(i)*basis(:, i)
    end do
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
