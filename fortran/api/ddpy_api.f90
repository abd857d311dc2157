!> The doorway of the core: flat arrays and C-bound procedures that f2py wraps
!> (fortran/ddpy_core.pyf). Scalars in are passed by value, everything else by reference.
!> Indices arriving from Python are 0-based and converted here; nothing here prints or stops.
module ddpy_api
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char
  use ddpy_kinds, only: wp
  use ddpy_bezier, only: max_bezier_degree, bezier_power_coefficients, bezier_de_casteljau
  use ddpy_nagata, only: nagata_patch_coefficients, nagata_edge_coefficient, &
                         nagata_coefficient_count
  use ddpy_surface, only: bezier_evaluate_batch, nagata_evaluate_batch
  use ddpy_linear_solver, only: solver_create, solver_analyse, solver_factorize, &
                                solver_solve, solver_destroy, solver_info, &
                                solver_set_control, solver_set_real_control, &
                                solver_set_ordering, solver_world, solver_serve, &
                                solver_finish, solver_analyse_elements, status_bad_handle, &
                                status_not_analysed, status_size_mismatch, &
                                status_no_free_handle, status_finished, status_not_host, &
                                status_not_positive_definite, solver_info_values, &
                                status_bad_precision, precision_double, precision_single, &
                                status_single_too_coarse, &
                                solver_precision, &
                                solver_flops, info_infog1, info_infog2, info_ordering, &
                                info_factor_entries, info_estimated_factor_entries, &
                                info_estimated_memory_mb_max, &
                                info_estimated_memory_mb_total, info_memory_mb_max, &
                                info_memory_mb_total, info_memory_used_mb_max, &
                                info_memory_used_mb_total, info_processes, &
                                info_negative_pivots, info_workspace_given, &
                                flops_elimination, flops_estimate
  use ddpy_handle_table, only: valid_handle, free_entry, max_handles, entry_solver, &
                               entry_blank, entry_surface, entry_problem, refusal_handle, &
                               refusal_size, refusal_index, refusal_full, refusal_value, &
                               refusal_order
  use ddpy_surface, only: surface_bezier, surface_nagata, bezier_stride, nagata_stride
  use ddpy_global_search, only: search_mode_tree, search_mode_brute, contact_none, &
                                contact_inside, contact_edge, memory_rows
  use ddpy_contact, only: contact_inactive, contact_stick, contact_slip
  use ddpy_material, only: material_prop_count, table_max_points, table_start, &
                           kinematic_rate, hardening_swift, hardening_voce, hardening_table, &
                           prop_young, prop_poisson, prop_hill, prop_law, prop_hardening
  use ddpy_solid_assembly, only: kind_hexahedron, kind_solid_shell, shell_modes, &
                                 status_back_size
  use ddpy_hex8, only: hex8_ok, hex8_inverted, hex8_material_failed
  use ddpy_solid_shell, only: shell_not_converged
  use ddpy_api_solid, only: status_bad_node, status_bad_offsets, status_bad_blank
  use ddpy_forming_data, only: contact_node, contact_surface, contact_gauss, max_face_order
  use ddpy_forming_problem, only: search_none, search_monotonicity, search_energy, &
                                  outcome_converged, outcome_landing, outcome_element, &
                                  outcome_not_finite, outcome_solver, outcome_stalled, &
                                  outcome_hold, hold_no_stiffness, hold_too_far, &
                                  history_width, history_residual, history_relative_residual, &
                                  history_relative_correction, history_step, &
                                  history_points_switched, history_pairs_switched, &
                                  history_yield_switched, history_relative_error
  !$ use omp_lib, only: omp_get_max_threads, omp_set_num_threads
  implicit none
  private
  public :: api_max_threads, api_set_threads, api_bezier_power_coefficients, &
            api_bezier_evaluate, api_bezier_de_casteljau, api_nagata_coefficients, &
            api_nagata_evaluate, api_nagata_edge_coefficient, api_solver_create, &
            api_solver_analyse, api_solver_factorize, api_solver_precision, &
            api_solver_solve, api_solver_info, &
            api_solver_destroy, api_solver_set_control, api_solver_set_real_control, &
            api_solver_set_ordering, api_solver_world, api_solver_serve, api_solver_finish, &
            api_solver_analyse_elements, api_core_constant_count, api_core_constants, &
            api_handle_release

  !> Characters of a constant's name in core_constants.
  integer, parameter :: name_length = 40

  integer, parameter :: nb = max_bezier_degree
  integer, parameter :: nc = nagata_coefficient_count

contains

  !> Threads an OpenMP region of the core would use (1 when built without OpenMP).
  subroutine api_max_threads(n) bind(C, name="ddpy_max_threads")
    integer(c_int), intent(out) :: n
    n = 1
    !$ n = omp_get_max_threads()
  end subroutine api_max_threads

  !> Set the number of threads of the core's OpenMP regions.
  subroutine api_set_threads(n) bind(C, name="ddpy_set_threads")
    integer(c_int), value, intent(in) :: n
    !$ if (n > 0) call omp_set_num_threads(n)
  end subroutine api_set_threads

  !> Power-basis coefficients of Bezier patches from their Bernstein control nets.
  !> info = 0, or the 1-based index of the first patch with a degree outside 1..6.
  subroutine api_bezier_power_coefficients(npatch, degrees, control, coef, info) &
    bind(C, name="ddpy_bezier_power_coefficients")
    integer(c_int), value, intent(in) :: npatch
    integer(c_int), intent(in) :: degrees(2, npatch)
    real(c_double), intent(in) :: control(3, 0:nb, 0:nb, npatch)
    real(c_double), intent(out) :: coef(3, 0:nb, 0:nb, npatch)
    integer(c_int), intent(out) :: info
    integer :: p
    info = 0
    do p = 1, npatch
      if (any(degrees(:, p) < 1) .or. any(degrees(:, p) > nb)) then
        info = p
        coef = 0.0_wp
        return
      end if
    end do
    !$omp parallel do schedule(static) if(npatch > 256)
    do p = 1, npatch
      call bezier_power_coefficients(degrees(1, p), degrees(2, p), control(:, :, :, p), &
                                     coef(:, :, :, p))
    end do
    !$omp end parallel do
  end subroutine api_bezier_power_coefficients

  !> Point, derivatives, unit normal and second derivatives of Bezier patches at k points.
  subroutine api_bezier_evaluate(npatch, degrees, coef, k, patch, params, points, derivs, &
                                 normals, second, info) bind(C, name="ddpy_bezier_evaluate")
    integer(c_int), value, intent(in) :: npatch, k
    integer(c_int), intent(in) :: degrees(2, npatch), patch(k)
    real(c_double), intent(in) :: coef(3, 0:nb, 0:nb, npatch), params(2, k)
    real(c_double), intent(out) :: points(3, k), derivs(3, 2, k), normals(3, k), &
                                   second(3, 3, k)
    integer(c_int), intent(out) :: info
    call bezier_evaluate_batch(npatch, degrees, coef, k, patch + 1, params, points, derivs, &
                               normals, second, info)
  end subroutine api_bezier_evaluate

  !> Points of Bezier patches by de Casteljau on the control nets (cross-check).
  subroutine api_bezier_de_casteljau(npatch, degrees, control, k, patch, params, points, &
                                     info) bind(C, name="ddpy_bezier_de_casteljau")
    integer(c_int), value, intent(in) :: npatch, k
    integer(c_int), intent(in) :: degrees(2, npatch), patch(k)
    real(c_double), intent(in) :: control(3, 0:nb, 0:nb, npatch), params(2, k)
    real(c_double), intent(out) :: points(3, k)
    integer(c_int), intent(out) :: info
    integer :: i, p
    info = 0
    points = 0.0_wp
    do i = 1, k
      p = patch(i) + 1
      if (p < 1 .or. p > npatch) then
        info = i
        return
      end if
      call bezier_de_casteljau(degrees(1, p), degrees(2, p), control(:, :, :, p), &
                               params(1, i), params(2, i), points(:, i))
    end do
  end subroutine api_bezier_de_casteljau

  !> Nagata (smooth /= 0) or facet (smooth = 0) coefficients of every face.
  !> faces(:, f) holds 0-based vertex indices, faces(4, f) = -1 for a triangle;
  !> corner_normals(:, c, f) is the unit normal of face f at its corner c; ratio_limit is
  !> the degenerate-normal limit of nagata_edge_coefficient.
  !> info = 0, or the 1-based index of the first face with a vertex index out of range.
  subroutine api_nagata_coefficients(nvert, vertices, nface, faces, corner_normals, smooth, &
                                     ratio_limit, coef, info) bind(C, name="ddpy_nagata_coefficients")
    integer(c_int), value, intent(in) :: nvert, nface, smooth
    real(c_double), value, intent(in) :: ratio_limit
    real(c_double), intent(in) :: vertices(3, nvert), corner_normals(3, 4, nface)
    integer(c_int), intent(in) :: faces(4, nface)
    real(c_double), intent(out) :: coef(3, nc, nface)
    integer(c_int), intent(out) :: info
    integer :: f, nv, c
    real(wp) :: x(3, 4)
    info = 0
    do f = 1, nface
      nv = merge(3, 4, faces(4, f) < 0)
      if (any(faces(1:nv, f) < 0) .or. any(faces(1:nv, f) >= nvert)) then
        info = f
        coef = 0.0_wp
        return
      end if
    end do
    !$omp parallel do schedule(static) private(nv, x, c) if(nface > 256)
    do f = 1, nface
      nv = merge(3, 4, faces(4, f) < 0)
      x = 0.0_wp
      do c = 1, nv
        x(:, c) = vertices(:, faces(c, f) + 1)
      end do
      call nagata_patch_coefficients(nv, x, corner_normals(:, :, f), smooth /= 0, &
                                     ratio_limit, coef(:, :, f))
    end do
    !$omp end parallel do
  end subroutine api_nagata_coefficients

  !> Point, derivatives, unit normal and second derivatives of Nagata patches at k points.
  subroutine api_nagata_evaluate(npatch, coef, k, patch, params, points, derivs, normals, &
                                 second, info) bind(C, name="ddpy_nagata_evaluate")
    integer(c_int), value, intent(in) :: npatch, k
    integer(c_int), intent(in) :: patch(k)
    real(c_double), intent(in) :: coef(3, nc, npatch), params(2, k)
    real(c_double), intent(out) :: points(3, k), derivs(3, 2, k), normals(3, k), &
                                   second(3, 3, k)
    integer(c_int), intent(out) :: info
    call nagata_evaluate_batch(npatch, coef, k, patch + 1, params, points, derivs, normals, &
                               second, info)
  end subroutine api_nagata_evaluate

  !> Nagata edge coefficients of m edges (x0 -> x1 with end normals n0, n1).
  subroutine api_nagata_edge_coefficient(m, x0, x1, n0, n1, ratio_limit, c) &
    bind(C, name="ddpy_nagata_edge_coefficient")
    integer(c_int), value, intent(in) :: m
    real(c_double), intent(in) :: x0(3, m), x1(3, m), n0(3, m), n1(3, m)
    real(c_double), value, intent(in) :: ratio_limit
    real(c_double), intent(out) :: c(3, m)
    integer :: i
    do i = 1, m
      c(:, i) = nagata_edge_coefficient(x0(:, i), x1(:, i), n0(:, i), n1(:, i), ratio_limit)
    end do
  end subroutine api_nagata_edge_coefficient

  subroutine api_solver_create(sym, ordering, precision, handle, status) &
    bind(C, name="ddpy_solver_create")
    integer(c_int), value, intent(in) :: sym, ordering, precision
    integer(c_int), intent(out) :: handle, status
    call solver_create(sym, ordering, precision, handle, status)
  end subroutine api_solver_create

  !> The precision of a solver's factors (the constants precision_*).
  subroutine api_solver_precision(handle, precision, status) &
    bind(C, name="ddpy_solver_precision")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: precision, status
    call solver_precision(handle, precision, status)
  end subroutine api_solver_precision

  !> Analyse the structure given by 0-based (row, col) coordinates.
  subroutine api_solver_analyse(handle, n, nz, irn, jcn, status) &
    bind(C, name="ddpy_solver_analyse")
    integer(c_int), value, intent(in) :: handle, n, nz
    integer(c_int), intent(in) :: irn(nz), jcn(nz)
    integer(c_int), intent(out) :: status
    call solver_analyse(handle, n, nz, irn + 1, jcn + 1, status)
  end subroutine api_solver_analyse

  !> Analyse the structure of nelt elements of k variables each, 0-based (MUMPS's estimates).
  subroutine api_solver_analyse_elements(handle, n, k, nelt, vars, status) &
    bind(C, name="ddpy_solver_analyse_elements")
    integer(c_int), value, intent(in) :: handle, n, k, nelt
    integer(c_int), intent(in) :: vars(k, nelt)
    integer(c_int), intent(out) :: status
    integer :: e
    call solver_analyse_elements(handle, n, nelt, k*nelt, [(1 + k*e, e = 0, nelt)], &
                                 reshape(vars + 1, [k*nelt]), status)
  end subroutine api_solver_analyse_elements

  subroutine api_solver_factorize(handle, nz, a, status) bind(C, name="ddpy_solver_factorize")
    integer(c_int), value, intent(in) :: handle, nz
    real(c_double), intent(in) :: a(nz)
    integer(c_int), intent(out) :: status
    call solver_factorize(handle, nz, a, status)
  end subroutine api_solver_factorize

  subroutine api_solver_solve(handle, n, rhs, x, status) bind(C, name="ddpy_solver_solve")
    integer(c_int), value, intent(in) :: handle, n
    real(c_double), intent(in) :: rhs(n)
    real(c_double), intent(out) :: x(n)
    integer(c_int), intent(out) :: status
    call solver_solve(handle, n, rhs, x, status)
  end subroutine api_solver_solve

  subroutine api_solver_info(handle, values, flops, status) bind(C, name="ddpy_solver_info")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: values(solver_info_values)
    real(c_double), intent(out) :: flops(solver_flops)
    integer(c_int), intent(out) :: status
    call solver_info(handle, values, flops, status)
  end subroutine api_solver_info

  subroutine api_solver_set_control(handle, index, value, status) &
    bind(C, name="ddpy_solver_set_control")
    integer(c_int), value, intent(in) :: handle, index, value
    integer(c_int), intent(out) :: status
    call solver_set_control(handle, index, value, status)
  end subroutine api_solver_set_control

  subroutine api_solver_set_real_control(handle, index, value, status) &
    bind(C, name="ddpy_solver_set_real_control")
    integer(c_int), value, intent(in) :: handle, index
    real(c_double), value, intent(in) :: value
    integer(c_int), intent(out) :: status
    call solver_set_real_control(handle, index, value, status)
  end subroutine api_solver_set_real_control

  !> Pivot order for the next analyses: perm(i) the 0-based position of variable i.
  subroutine api_solver_set_ordering(handle, n, perm, status) &
    bind(C, name="ddpy_solver_set_ordering")
    integer(c_int), value, intent(in) :: handle, n
    integer(c_int), intent(in) :: perm(n)
    integer(c_int), intent(out) :: status
    call solver_set_ordering(handle, n, perm + 1, status)
  end subroutine api_solver_set_ordering

  subroutine api_solver_destroy(handle, status) bind(C, name="ddpy_solver_destroy")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: status
    call solver_destroy(handle, status)
  end subroutine api_solver_destroy

  !> This process's MPI rank, the number of processes (starts MPI when needed) and whether
  !> the build has the parallel MUMPS (1) or the sequential one (0).
  subroutine api_solver_world(rank, size, parallel, status) bind(C, name="ddpy_solver_world")
    integer(c_int), intent(out) :: rank, size, parallel, status
    call solver_world(rank, size, parallel, status)
  end subroutine api_solver_world

  !> Ranks > 0: serve rank 0's solver commands until it finishes.
  subroutine api_solver_serve(status) bind(C, name="ddpy_solver_serve")
    integer(c_int), intent(out) :: status
    call solver_serve(status)
  end subroutine api_solver_serve

  !> Rank 0: free every solver, stop the ranks > 0, end MPI.
  subroutine api_solver_finish(status) bind(C, name="ddpy_solver_finish")
    integer(c_int), intent(out) :: status
    call solver_finish(status)
  end subroutine api_solver_finish

  !> Free what a handle of the core's table holds: a blank, a tool surface, a forming
  !> problem, or a MUMPS instance (solver_destroy). status: 0, or refusal_handle.
  subroutine api_handle_release(handle, status) bind(C, name="ddpy_handle_release")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: status
    if (valid_handle(handle, entry_solver)) then
      call solver_destroy(handle, status)
      return
    end if
    status = refusal_handle
    if (.not. (valid_handle(handle, entry_blank) .or. valid_handle(handle, entry_surface) &
               .or. valid_handle(handle, entry_problem))) return
    call free_entry(handle)
    status = 0
  end subroutine api_handle_release

  !> The number of constants core_constants exports.
  subroutine api_core_constant_count(n) bind(C, name="ddpy_core_constant_count")
    integer(c_int), intent(out) :: n
    n = 0
    call constant_table(n)
  end subroutine api_core_constant_count

  !> Every count, code and index that Python and the core share, by name (n of them, each
  !> name name_length characters, blank-padded): element kinds and statuses, the material
  !> vector's layout, surface kinds and strides, search modes and projection statuses,
  !> contact states and discretizations, line searches, the Newton loop's outcomes and
  !> history columns, the refusals of the handle table and the linear solver's statuses.
  !> Offsets are 0-based positions in a Python array.
  subroutine api_core_constants(n, names, values) bind(C, name="ddpy_core_constants")
    integer(c_int), value, intent(in) :: n
    character(kind=c_char), intent(out) :: names(name_length, n)
    integer(c_int), intent(out) :: values(n)
    integer(c_int) :: m
    m = n
    call constant_table(m, names, values)
  end subroutine api_core_constants

  !> The constants (see api_core_constants): their count m, and the first n of them into
  !> names and values where given.
  subroutine constant_table(m, names, values)
    integer(c_int), intent(inout) :: m
    character(kind=c_char), intent(out), optional :: names(:, :)
    integer(c_int), intent(out), optional :: values(:)
    integer :: n
    n = m
    m = 0
    call add('element_hexahedron', kind_hexahedron)
    call add('element_solid_shell', kind_solid_shell)
    call add('shell_modes', shell_modes)
    call add('element_ok', hex8_ok)
    call add('element_inverted', hex8_inverted)
    call add('element_material_failed', hex8_material_failed)
    call add('element_bad_node', status_bad_node)
    call add('element_bad_offsets', status_bad_offsets)
    call add('element_not_converged', shell_not_converged)
    call add('element_back_size', status_back_size)
    call add('element_bad_blank', status_bad_blank)
    call add('material_prop_count', material_prop_count)
    call add('material_table_max_points', table_max_points)
    call add('material_table_offset', table_start)
    call add('material_kinematic_offset', kinematic_rate - 1)
    call add('material_young_offset', prop_young - 1)
    call add('material_poisson_offset', prop_poisson - 1)
    call add('material_hill_offset', prop_hill - 1)
    call add('material_law_offset', prop_law - 1)
    call add('material_hardening_offset', prop_hardening - 1)
    call add('hardening_swift', hardening_swift)
    call add('hardening_voce', hardening_voce)
    call add('hardening_table', hardening_table)
    call add('surface_bezier', surface_bezier)
    call add('surface_nagata', surface_nagata)
    call add('bezier_stride', bezier_stride)
    call add('nagata_stride', nagata_stride)
    call add('search_mode_tree', search_mode_tree)
    call add('search_mode_brute', search_mode_brute)
    call add('projection_none', contact_none)
    call add('projection_inside', contact_inside)
    call add('projection_edge', contact_edge)
    call add('search_memory_rows', memory_rows)
    call add('contact_open', contact_inactive)
    call add('contact_stick', contact_stick)
    call add('contact_slip', contact_slip)
    call add('discretization_node', contact_node)
    call add('discretization_surface', contact_surface)
    call add('discretization_gauss', contact_gauss)
    call add('max_face_order', max_face_order)
    call add('line_search_none', search_none)
    call add('line_search_monotonicity', search_monotonicity)
    call add('line_search_energy', search_energy)
    call add('outcome_converged', outcome_converged)
    call add('outcome_landing', outcome_landing)
    call add('outcome_element', outcome_element)
    call add('outcome_not_finite', outcome_not_finite)
    call add('outcome_solver', outcome_solver)
    call add('outcome_stalled', outcome_stalled)
    call add('outcome_hold', outcome_hold)
    call add('hold_no_stiffness', hold_no_stiffness)
    call add('hold_too_far', hold_too_far)
    call add('history_width', history_width)
    call add('history_residual_offset', history_residual - 1)
    call add('history_relative_residual_offset', history_relative_residual - 1)
    call add('history_relative_correction_offset', history_relative_correction - 1)
    call add('history_step_offset', history_step - 1)
    call add('history_points_switched_offset', history_points_switched - 1)
    call add('history_pairs_switched_offset', history_pairs_switched - 1)
    call add('history_yield_switched_offset', history_yield_switched - 1)
    call add('history_relative_error_offset', history_relative_error - 1)
    call add('max_handles', max_handles)
    call add('refusal_handle', refusal_handle)
    call add('refusal_size', refusal_size)
    call add('refusal_index', refusal_index)
    call add('refusal_full', refusal_full)
    call add('refusal_value', refusal_value)
    call add('refusal_order', refusal_order)
    call add('solver_info_values', solver_info_values)
    call add('solver_flops', solver_flops)
    call add('info_infog1_offset', info_infog1 - 1)
    call add('info_infog2_offset', info_infog2 - 1)
    call add('info_ordering_offset', info_ordering - 1)
    call add('info_factor_entries_offset', info_factor_entries - 1)
    call add('info_estimated_factor_entries_offset', info_estimated_factor_entries - 1)
    call add('info_estimated_memory_mb_max_offset', info_estimated_memory_mb_max - 1)
    call add('info_estimated_memory_mb_total_offset', info_estimated_memory_mb_total - 1)
    call add('info_memory_mb_max_offset', info_memory_mb_max - 1)
    call add('info_memory_mb_total_offset', info_memory_mb_total - 1)
    call add('info_memory_used_mb_max_offset', info_memory_used_mb_max - 1)
    call add('info_memory_used_mb_total_offset', info_memory_used_mb_total - 1)
    call add('info_processes_offset', info_processes - 1)
    call add('info_negative_pivots_offset', info_negative_pivots - 1)
    call add('info_workspace_given_offset', info_workspace_given - 1)
    call add('flops_elimination_offset', flops_elimination - 1)
    call add('flops_estimate_offset', flops_estimate - 1)
    call add('solver_bad_handle', status_bad_handle)
    call add('solver_not_analysed', status_not_analysed)
    call add('solver_size_mismatch', status_size_mismatch)
    call add('solver_no_free_handle', status_no_free_handle)
    call add('solver_finished', status_finished)
    call add('solver_not_host', status_not_host)
    call add('solver_not_positive_definite', status_not_positive_definite)
    call add('solver_bad_precision', status_bad_precision)
    call add('solver_single_too_coarse', status_single_too_coarse)
    call add('precision_double', precision_double)
    call add('precision_single', precision_single)

  contains

    subroutine add(name, value)
      character(len=*), intent(in) :: name
      integer, intent(in) :: value
      integer :: j
      m = m + 1
      if (m > n) return
      if (present(values)) values(m) = value
      if (present(names)) then
        do j = 1, name_length
          names(j, m) = ' '
          if (j <= len(name)) names(j, m) = name(j:j)
        end do
      end if
    end subroutine add

  end subroutine constant_table

end module ddpy_api
