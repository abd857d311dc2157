!> One tool surface with everything its contact search reads: the patches' coefficients, the
!> box tree over their bounds, the boxes in the patches' own frames and the grid that starts
!> the local search (ddpy_global_search). Made once per tool from what ddpy.geometry.search
!> built (its ContactSearch keeps one in the core's handle table); the forming problem
!> holds a copy per tool.
module ddpy_search_surface
  use ddpy_kinds, only: wp
  use ddpy_global_search, only: contact_search, memory_rows
  implicit none
  private
  public :: search_surface, surface_build, surface_contact_search

  !> A tool surface and its search structures. Indices of the tree's children and of the
  !> grid's first points are 1-based and local to the surface.
  type :: search_surface
    !> Surface kind (ddpy_surface: surface_bezier, surface_nagata), reals per patch, patches.
    integer :: kind = 0, stride = 0, npatch = 0
    !> The search's mode (search_mode_tree or search_mode_brute), its local search's Newton
    !> iterations at most and tolerance.
    integer :: mode = 0, max_iterations = 0
    real(wp) :: tol = 0.0_wp
    real(wp), allocatable :: coef(:, :)            !< (stride, npatch)
    integer, allocatable :: degrees(:, :)          !< (2, npatch), Bezier patches only
    integer, allocatable :: triangle(:)            !< (npatch), 1 for a triangle
    real(wp), allocatable :: tree_lower(:, :), tree_upper(:, :)  !< (3, 2 npatch - 1)
    integer, allocatable :: tree_child(:)          !< (2 npatch - 1)
    real(wp), allocatable :: frame(:, :, :)        !< (3, 3, npatch)
    real(wp), allocatable :: frame_lower(:, :), frame_upper(:, :)  !< (3, npatch)
    integer, allocatable :: grid_start(:)          !< (npatch + 1)
    real(wp), allocatable :: grid_params(:, :)     !< (2, ngrid)
    real(wp), allocatable :: grid_normals(:, :), grid_points(:, :)  !< (3, ngrid)
  end type search_surface

contains

  !> The surface of npatch patches (coef, degrees, triangle) with its box tree (ntree =
  !> 2 npatch - 1 nodes, ddpy_box_tree: children 1-based, a leaf -patch), its frame boxes
  !> (ddpy_patch_bounds), its grid of ngrid points (grid_start 1-based, grid_start(npatch +
  !> 1) = ngrid + 1) and its search settings. ok is false where they do not fit: no patch,
  !> a tree of another size or with a child out of range, a grid out of order.
  pure subroutine surface_build(kind, npatch, stride, coef, degrees, triangle, ntree, &
                                tree_lower, tree_upper, tree_child, frame, frame_lower, &
                                frame_upper, ngrid, grid_start, grid_params, grid_normals, &
                                grid_points, mode, max_iterations, tol, surface, ok)
    integer, intent(in) :: kind, npatch, stride, ntree, ngrid, mode, max_iterations
    real(wp), intent(in) :: coef(stride, npatch), tree_lower(3, ntree), tree_upper(3, ntree), &
                            frame(3, 3, npatch), frame_lower(3, npatch), &
                            frame_upper(3, npatch), grid_params(2, ngrid), &
                            grid_normals(3, ngrid), grid_points(3, ngrid), tol
    integer, intent(in) :: degrees(2, npatch), triangle(npatch), tree_child(ntree), &
                           grid_start(npatch + 1)
    type(search_surface), intent(out) :: surface
    logical, intent(out) :: ok
    ok = npatch >= 1 .and. stride >= 1 .and. ntree == 2*npatch - 1
    if (.not. ok) return
    ok = all(tree_child >= -npatch .and. tree_child /= 0 .and. tree_child < ntree) .and. &
         grid_start(1) == 1 .and. grid_start(npatch + 1) == ngrid + 1 .and. &
         all(grid_start(2:) >= grid_start(:npatch))
    if (.not. ok) return
    surface%kind = kind
    surface%stride = stride
    surface%npatch = npatch
    surface%mode = mode
    surface%max_iterations = max_iterations
    surface%tol = tol
    surface%coef = coef
    surface%degrees = degrees
    surface%triangle = triangle
    surface%tree_lower = tree_lower
    surface%tree_upper = tree_upper
    surface%tree_child = tree_child
    surface%frame = frame
    surface%frame_lower = frame_lower
    surface%frame_upper = frame_upper
    surface%grid_start = grid_start
    surface%grid_params = grid_params
    surface%grid_normals = grid_normals
    surface%grid_points = grid_points
  end subroutine surface_build

  !> Global and local search of k points against the surface moved by displacement, in the
  !> given mode (see contact_search for the rest: the facing filter by node_normals, the
  !> reach, lock (1-based patches; 0 searches) and the outputs, patch 1-based).
  subroutine surface_contact_search(surface, mode, k, nodes, node_normals, displacement, reach, &
                            lock, patch, params, points, normals, tangents, distance, status, &
                            iterations, ncandidates, nmemory, memory, memory_patch)
    type(search_surface), intent(in) :: surface
    integer, intent(in) :: mode, k, lock(k), nmemory
    real(wp), intent(inout) :: memory(memory_rows, nmemory)
    integer, intent(inout) :: memory_patch(nmemory)
    real(wp), intent(in) :: nodes(3, k), node_normals(3, k), displacement(3), reach
    integer, intent(out) :: patch(k), status(k), iterations(k), ncandidates(k)
    real(wp), intent(out) :: params(2, k), points(3, k), normals(3, k), tangents(3, 2, k), &
                             distance(k)
    call contact_search(surface%kind, surface%npatch, surface%stride, surface%coef, &
                        surface%degrees, surface%triangle, mode, 2*surface%npatch - 1, &
                        surface%tree_lower, surface%tree_upper, surface%tree_child, &
                        surface%frame, surface%frame_lower, surface%frame_upper, &
                        size(surface%grid_params, 2), surface%grid_start, &
                        surface%grid_params, surface%grid_normals, surface%grid_points, k, &
                        nodes, node_normals, displacement, surface%max_iterations, &
                        surface%tol, reach, lock, patch, params, points, normals, tangents, &
                        distance, status, iterations, ncandidates, nmemory, memory, &
                        memory_patch)
  end subroutine surface_contact_search

end module ddpy_search_surface
