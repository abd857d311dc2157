!> f2py doorway of the contact search (see ddpy_api.f90 for the conventions).
!> Patch and point indices arriving from Python are 0-based, except the index structures
!> that Python builds once per tool for the core alone (the tree's children, and grid_start
!> of the search): those are 1-based, so that no call makes 1-based copies of them.
module ddpy_api_search
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_patch_bounds, only: patch_bounds
  use ddpy_box_tree, only: box_tree_build
  use ddpy_global_search, only: contact_search
  implicit none
  private
  public :: api_search_tree, api_contact_search

contains

  !> The search tree of a tool of npatch patches (see ddpy_global_search): its ntree =
  !> 2 npatch - 1 node boxes and children (1-based, used only by the core), and the boxes
  !> of every patch in its own frame.
  subroutine api_search_tree(kind, npatch, stride, coef, degrees, triangle, ntree, &
                             tree_lower, tree_upper, tree_child, frame, frame_lower, &
                             frame_upper) bind(C, name="ddpy_search_tree")
    integer(c_int), value, intent(in) :: kind, npatch, stride, ntree
    real(c_double), intent(in) :: coef(stride, npatch)
    integer(c_int), intent(in) :: degrees(2, npatch), triangle(npatch)
    real(c_double), intent(out) :: tree_lower(3, ntree), tree_upper(3, ntree), &
                                   frame(3, 3, npatch), frame_lower(3, npatch), &
                                   frame_upper(3, npatch)
    integer(c_int), intent(out) :: tree_child(ntree)
    real(wp), allocatable :: lower(:, :), upper(:, :)
    if (npatch < 1 .or. ntree /= 2*npatch - 1) return
    allocate(lower(3, npatch), upper(3, npatch))
    call patch_bounds(kind, npatch, stride, coef, degrees, triangle, lower, upper, frame, &
                      frame_lower, frame_upper)
    call box_tree_build(npatch, lower, upper, tree_lower, tree_upper, tree_child)
  end subroutine api_search_tree

  !> Global and local search of nnode nodes against one tool (see ddpy_global_search);
  !> projections farther than reach are dropped (huge: no limit).
  !> tree_child and grid_start arrive 1-based (see above); held (0-based, -1: search) the
  !> patch each node is held on.
  !> Outputs: patch (0-based, -1 for none), parameters, closest point (moved with the tool),
  !> unit normal, tangents, signed normal distance, status, Newton iterations, projections.
  subroutine api_contact_search(kind, npatch, stride, coef, degrees, triangle, mode, ntree, &
                                tree_lower, tree_upper, tree_child, frame, frame_lower, &
                                frame_upper, ngrid, grid_start, grid_params, grid_normals, &
                                grid_points, nnode, nodes, node_normals, tool_displacement, &
                                max_iterations, tol, reach, held, patch, params, points, &
                                normals, tangents, distance, status, iterations, &
                                ncandidates) &
    bind(C, name="ddpy_contact_search")
    integer(c_int), value, intent(in) :: kind, npatch, stride, mode, ntree, ngrid, nnode, &
                                         max_iterations
    real(c_double), value, intent(in) :: tol, reach
    real(c_double), intent(in) :: coef(stride, npatch), tree_lower(3, ntree), &
                                  tree_upper(3, ntree), frame(3, 3, npatch), &
                                  frame_lower(3, npatch), frame_upper(3, npatch), &
                                  grid_params(2, ngrid), grid_normals(3, ngrid), &
                                  grid_points(3, ngrid), nodes(3, nnode), &
                                  node_normals(3, nnode), tool_displacement(3)
    integer(c_int), intent(in) :: degrees(2, npatch), triangle(npatch), tree_child(ntree), &
                                  grid_start(npatch + 1), held(nnode)
    integer(c_int), intent(out) :: patch(nnode), status(nnode), iterations(nnode), &
                                   ncandidates(nnode)
    real(c_double), intent(out) :: params(2, nnode), points(3, nnode), normals(3, nnode), &
                                   tangents(3, 2, nnode), distance(nnode)
    integer, allocatable :: lock(:)
    allocate(lock(nnode))
    lock = merge(held + 1, 0, held >= 0 .and. held < npatch)  ! 1-based; 0: search
    call contact_search(kind, npatch, stride, coef, degrees, triangle, mode, ntree, &
                        tree_lower, tree_upper, tree_child, frame, frame_lower, frame_upper, &
                        ngrid, grid_start, grid_params, grid_normals, grid_points, nnode, &
                        nodes, node_normals, tool_displacement, max_iterations, tol, reach, &
                        lock, patch, params, points, normals, tangents, distance, status, &
                        iterations, ncandidates)
    patch = patch - 1
  end subroutine api_contact_search

end module ddpy_api_search
