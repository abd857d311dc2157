!> f2py doorway of the forming problem's contact (see ddpy_api.f90 for the conventions and
!> ddpy_forming for the arguments). Node indices arrive 0-based.
module ddpy_api_forming
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_forming, only: forming_contact, tool_fields
  use ddpy_forming_newton, only: forming_increment, newton_settings, newton_integer_settings, &
                                 penetration_step
  use ddpy_material, only: material_prop_count
  implicit none
  private
  public :: api_forming_contact, api_forming_increment, api_penetration_step

contains

  !> Contact of every (tool, slave) pair: see forming_contact.
  subroutine api_forming_contact(nnode, x, x_n, fixed, ntool, table, tol, ncoef, coef, &
                                 ndeg, degrees, ntri, triangle, ntree, tree_lower, &
                                 tree_upper, tree_child, nframe, frame, frame_lower, &
                                 frame_upper, nstart, grid_start, ngrid, grid_params, &
                                 grid_normals, grid_points, facing, face_first, nface, &
                                 faces, corner, positions, positions_n, reach, size, &
                                 touching, resting, npair, tool_first, pair_node, on, force, &
                                 r, mu, held, eqn, nf, k_slots, nvalues, residual, values, &
                                 state, gap, normal) bind(C, name="ddpy_forming_contact")
    integer(c_int), value, intent(in) :: nnode, ntool, ncoef, ndeg, ntri, ntree, nframe, &
                                         nstart, ngrid, nface, resting, npair, nf, k_slots, &
                                         nvalues
    real(c_double), value, intent(in) :: reach, size, touching
    real(c_double), intent(in) :: x(3, nnode), x_n(3, nnode), tol(ntool), coef(ncoef), &
                                  tree_lower(3*ntree), tree_upper(3*ntree), frame(9*nframe), &
                                  frame_lower(3*nframe), frame_upper(3*nframe), &
                                  grid_params(2*ngrid), grid_normals(3*ngrid), &
                                  grid_points(3*ngrid), facing(3, ntool), &
                                  positions(3, ntool), positions_n(3, ntool), &
                                  force(3, npair), r(npair), mu(npair)
    integer(c_int), intent(in) :: fixed(3, nnode), table(tool_fields, ntool), degrees(ndeg), &
                                  triangle(ntri), tree_child(ntree), grid_start(nstart), &
                                  face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                                  tool_first(ntool + 1), pair_node(npair), on(npair), &
                                  held(3, npair), eqn(3, nnode)
    real(c_double), intent(inout) :: residual(nf + 3*npair), values(nvalues)
    integer(c_int), intent(out) :: state(npair)
    real(c_double), intent(out) :: gap(npair), normal(3, npair)
    call forming_contact(nnode, x, x_n, fixed, ntool, table, tol, coef, degrees, triangle, &
                         tree_lower, tree_upper, tree_child, frame, frame_lower, frame_upper, &
                         grid_start, grid_params, grid_normals, grid_points, facing, &
                         face_first, nface, faces, corner, positions, positions_n, reach, &
                         size, touching, resting, npair, tool_first, pair_node, on, force, r, &
                         mu, held, eqn, nf, k_slots, nvalues, residual, values, state, gap, &
                         normal)
  end subroutine api_forming_contact

  !> Newton iterations of one increment: see forming_increment. Connectivity arrives 0-based.
  subroutine api_forming_increment(nnode, x0, ne, conn, props, u_ref, axes_old, stress_old, &
                                   ep_old, strain_old, eqn, offsets, fixed, nf, k_slots, &
                                   n_coupling, nvalues, rows, cols, ntool, table, tol, ncoef, &
                                   coef, ndeg, degrees, ntri, triangle, ntree, tree_lower, &
                                   tree_upper, tree_child, nframe, frame, frame_lower, &
                                   frame_upper, nstart, grid_start, ngrid, grid_params, &
                                   grid_normals, grid_points, facing, face_first, nface, &
                                   faces, corner, positions, positions_n, reach, size, &
                                   touching, npair, tool_first, pair_node, on, r, mu, held, &
                                   u_n, force_n, external, guess, settings, isettings, &
                                   factored, reuse_next, u, force, stress, ep, strain, axes, &
                                   state, gap, normal, nhistory, niter, history, counters, &
                                   timings, outcome, info, detail) &
    bind(C, name="ddpy_forming_increment")
    integer(c_int), value, intent(in) :: nnode, ne, nf, k_slots, n_coupling, nvalues, ntool, &
                                         ncoef, ndeg, ntri, ntree, nframe, nstart, ngrid, &
                                         nface, npair, nhistory
    real(c_double), value, intent(in) :: reach, size, touching
    integer(c_int), intent(in) :: conn(8, ne), eqn(3, nnode), offsets(ne + 1), &
                                  fixed(3, nnode), rows(nvalues), cols(nvalues), &
                                  table(tool_fields, ntool), degrees(ndeg), triangle(ntri), &
                                  tree_child(ntree), grid_start(nstart), &
                                  face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                                  tool_first(ntool + 1), pair_node(npair), on(npair), &
                                  held(3, npair), isettings(newton_integer_settings)
    real(c_double), intent(in) :: x0(3, nnode), props(material_prop_count), &
                                  u_ref(3, nnode), axes_old(3, 3, 8, ne), &
                                  stress_old(6, 8, ne), ep_old(8, ne), strain_old(6, 8, ne), &
                                  tol(ntool), coef(ncoef), tree_lower(3*ntree), &
                                  tree_upper(3*ntree), frame(9*nframe), &
                                  frame_lower(3*nframe), frame_upper(3*nframe), &
                                  grid_params(2*ngrid), grid_normals(3*ngrid), &
                                  grid_points(3*ngrid), facing(3, ntool), &
                                  positions(3, ntool), positions_n(3, ntool), r(npair), &
                                  mu(npair), u_n(3, nnode), force_n(3, npair), &
                                  external(3, nnode), guess(3, nnode), &
                                  settings(newton_settings)
    integer(c_int), intent(inout) :: factored, reuse_next
    real(c_double), intent(out) :: u(3, nnode), force(3, npair), stress(6, 8, ne), ep(8, ne), &
                                   strain(6, 8, ne), axes(3, 3, 8, ne), gap(npair), &
                                   normal(3, npair), history(4, nhistory), timings(4), &
                                   detail(2)
    integer(c_int), intent(out) :: state(npair), niter, counters(5), outcome, info(4)
    history = 0.0_wp
    if (nhistory < isettings(1) + 1) then
      outcome = -1
      return
    end if
    call forming_increment(nnode, x0, ne, conn + 1, props, u_ref, axes_old, stress_old, &
                           ep_old, strain_old, eqn, offsets, fixed, nf, k_slots, n_coupling, &
                           nvalues, rows, cols, ntool, table, tol, coef, degrees, triangle, &
                           tree_lower, tree_upper, tree_child, frame, frame_lower, &
                           frame_upper, grid_start, grid_params, grid_normals, grid_points, &
                           facing, face_first, nface, faces, corner, positions, positions_n, &
                           reach, size, touching, npair, tool_first, pair_node, on, r, mu, &
                           held, u_n, force_n, external, guess, settings, isettings, &
                           factored, reuse_next, u, force, stress, ep, strain, axes, state, &
                           gap, normal, niter, history, counters, timings, outcome, info, &
                           detail)
  end subroutine api_forming_increment

  !> The step length the Newton loop's penetration limit allows (see penetration_step).
  subroutine api_penetration_step(nnode, npair, du, pair_node, on, state, gap, normal, &
                                  room_depth, min_step, step) &
    bind(C, name="ddpy_penetration_step")
    integer(c_int), value, intent(in) :: nnode, npair
    real(c_double), value, intent(in) :: room_depth, min_step
    real(c_double), intent(in) :: du(3, nnode), gap(npair), normal(3, npair)
    integer(c_int), intent(in) :: pair_node(npair), on(npair), state(npair)
    real(c_double), intent(out) :: step
    step = penetration_step(nnode, npair, du, pair_node, on, state, gap, normal, room_depth, &
                            min_step)
  end subroutine api_penetration_step

end module ddpy_api_forming
