!> f2py doorway of the contact search (see ddpy_api.f90 for the conventions).
!> Patch, point and vertex indices arriving from Python are 0-based, except the index
!> structures that Python builds once per tool for the core alone (cell_items, and group,
!> grid_start, vertex_patch_start and vertex_patches of the search): those are 1-based, so
!> that no call makes 1-based copies of them.
module ddpy_api_search
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_spatial_index, only: index_layout, index_build
  use ddpy_global_search, only: contact_search
  implicit none
  private
  public :: api_index_layout, api_index_build, api_contact_search

contains

  !> Origin, cell edge and cell counts of a spatial index over n points.
  subroutine api_index_layout(n, points, origin, h, dims) bind(C, name="ddpy_index_layout")
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: points(3, n)
    real(c_double), intent(out) :: origin(3), h
    integer(c_int), intent(out) :: dims(3)
    call index_layout(n, points, origin, h, dims)
  end subroutine api_index_layout

  !> Cell arrays of the index (1-based item numbers, used only by the core).
  subroutine api_index_build(n, points, origin, h, dims, ncell, cell_start, cell_items) &
    bind(C, name="ddpy_index_build")
    integer(c_int), value, intent(in) :: n, ncell
    real(c_double), intent(in) :: points(3, n), origin(3)
    real(c_double), value, intent(in) :: h
    integer(c_int), intent(in) :: dims(3)
    integer(c_int), intent(out) :: cell_start(ncell + 1), cell_items(n)
    call index_build(n, points, origin, h, dims, ncell, cell_start, cell_items)
  end subroutine api_index_build

  !> Global and local search of nnode nodes against one tool (see ddpy_global_search).
  !> group, grid_start, vertex_patch_start and vertex_patches arrive 1-based (see above).
  !> Outputs: patch (0-based, -1 for none), parameters, closest point (moved with the tool),
  !> unit normal, tangents, signed normal distance, status, Newton iterations, candidates.
  subroutine api_contact_search(kind, npatch, stride, coef, degrees, triangle, mode, npoint, &
                                index_points, group, origin, h, dims, ncell, cell_start, &
                                cell_items, ngrid, grid_start, grid_params, grid_normals, &
                                grid_points, nvertex, vertex_patch_start, nvp, vertex_patches, &
                                nnode, nodes, node_normals, tool_displacement, ncand, &
                                nvertex_query, max_iterations, tol, patch, params, points, &
                                normals, tangents, distance, status, iterations, ncandidates) &
    bind(C, name="ddpy_contact_search")
    integer(c_int), value, intent(in) :: kind, npatch, stride, mode, npoint, ncell, ngrid, &
                                         nvertex, nvp, nnode, ncand, nvertex_query, &
                                         max_iterations
    real(c_double), value, intent(in) :: h, tol
    real(c_double), intent(in) :: coef(stride, npatch), index_points(3, npoint), origin(3), &
                                  grid_params(2, ngrid), grid_normals(3, ngrid), &
                                  grid_points(3, ngrid), nodes(3, nnode), &
                                  node_normals(3, nnode), tool_displacement(3)
    integer(c_int), intent(in) :: degrees(2, npatch), triangle(npatch), group(npoint), &
                                  dims(3), cell_start(ncell + 1), cell_items(npoint), &
                                  grid_start(npatch + 1), vertex_patch_start(nvertex + 1), &
                                  vertex_patches(nvp)
    integer(c_int), intent(out) :: patch(nnode), status(nnode), iterations(nnode), &
                                   ncandidates(nnode)
    real(c_double), intent(out) :: params(2, nnode), points(3, nnode), normals(3, nnode), &
                                   tangents(3, 2, nnode), distance(nnode)
    call contact_search(kind, npatch, stride, coef, degrees, triangle, mode, npoint, &
                        index_points, group, origin, h, dims, ncell, cell_start, &
                        cell_items, ngrid, grid_start, grid_params, grid_normals, &
                        grid_points, nvertex, vertex_patch_start, nvp, vertex_patches, &
                        nnode, nodes, node_normals, tool_displacement, ncand, nvertex_query, &
                        max_iterations, tol, patch, params, points, normals, tangents, &
                        distance, status, iterations, ncandidates)
    patch = patch - 1
  end subroutine api_contact_search

end module ddpy_api_search
