!> f2py doorway of the forming problem's contact (see ddpy_api.f90 for the conventions and
!> ddpy_forming for the arguments). Node indices arrive 0-based.
module ddpy_api_forming
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_forming, only: forming_contact, tool_fields
  implicit none
  private
  public :: api_forming_contact

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

end module ddpy_api_forming
