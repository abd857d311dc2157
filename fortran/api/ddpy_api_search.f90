!> f2py doorway of the contact search (see ddpy_api.f90 for the conventions): a tool
!> surface with its search structures is made once, kept in the core's handle table, and
!> searched by its handle.
!> Patch and point indices arriving from Python are 0-based, except the index structures
!> that Python builds once per tool for the core alone (the tree's children, and grid_start
!> of the search): those are 1-based, so that no call makes 1-based copies of them.
module ddpy_api_search
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_patch_bounds, only: patch_bounds
  use ddpy_box_tree, only: box_tree_build
  use ddpy_global_search, only: search_mode_tree, search_mode_brute, memory_rows
  use ddpy_surface, only: surface_bezier, surface_nagata
  use ddpy_search_surface, only: search_surface, surface_build, surface_contact_search
  use ddpy_handle_table, only: table, claim_handle, valid_handle, entry_surface, &
                               refusal_handle, refusal_size, refusal_full, refusal_value
  implicit none
  private
  public :: api_search_tree, api_surface_create, api_contact_search

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

  !> A tool surface of npatch patches in the core's handle table (ddpy_search_surface): its
  !> coefficients, degrees and triangle flags, the tree and frame boxes search_tree made of
  !> them, its grid of ngrid points (grid_start 1-based, as ddpy.geometry.search builds
  !> it) and its search settings (mode, the local search's iterations at most and
  !> tolerance). status: 0, or a refusal of ddpy_handle_table.
  subroutine api_surface_create(kind, npatch, stride, coef, degrees, triangle, ntree, &
                                tree_lower, tree_upper, tree_child, frame, frame_lower, &
                                frame_upper, ngrid, grid_start, grid_params, grid_normals, &
                                grid_points, mode, max_iterations, tol, handle, status) &
    bind(C, name="ddpy_surface_create")
    integer(c_int), value, intent(in) :: kind, npatch, stride, ntree, ngrid, mode, &
                                         max_iterations
    real(c_double), value, intent(in) :: tol
    real(c_double), intent(in) :: coef(stride, npatch), tree_lower(3, ntree), &
                                  tree_upper(3, ntree), frame(3, 3, npatch), &
                                  frame_lower(3, npatch), frame_upper(3, npatch), &
                                  grid_params(2, ngrid), grid_normals(3, ngrid), &
                                  grid_points(3, ngrid)
    integer(c_int), intent(in) :: degrees(2, npatch), triangle(npatch), tree_child(ntree), &
                                  grid_start(npatch + 1)
    integer(c_int), intent(out) :: handle, status
    type(search_surface), allocatable :: surface
    logical :: ok
    handle = 0
    status = refusal_value
    if (kind /= surface_bezier .and. kind /= surface_nagata) return
    if (mode /= search_mode_tree .and. mode /= search_mode_brute) return
    if (max_iterations < 1) return
    allocate(surface)
    call surface_build(kind, npatch, stride, coef, degrees, triangle, ntree, tree_lower, &
                       tree_upper, tree_child, frame, frame_lower, frame_upper, ngrid, &
                       grid_start, grid_params, grid_normals, grid_points, mode, &
                       max_iterations, tol, surface, ok)
    status = refusal_size
    if (.not. ok) return
    status = refusal_full
    call claim_handle(entry_surface, handle)
    if (handle == 0) return
    call move_alloc(surface, table(handle)%surface)
    status = 0
  end subroutine api_surface_create

  !> Global and local search of nnode nodes against the tool surface behind handle
  !> surface (see ddpy_global_search), in the given mode, the tool moved by
  !> tool_displacement; projections farther than reach are dropped (huge: no limit).
  !> held (0-based, -1: search) the patch each node is held on.
  !> Outputs: patch (0-based, -1 for none), parameters, closest point (moved with the tool),
  !> unit normal, tangents, signed normal distance, status, Newton iterations, projections;
  !> memory (memory_rows, nmemory), memory_patch (nmemory): the search's memory of the nnode
  !> nodes (ddpy_global_search; memory_patch -1 for a node not searched yet), updated.
  !> refusal: 0, or refusal_handle (no such surface) with empty answers, refusal_size
  !> (a memory of another size than nnode).
  subroutine api_contact_search(surface, mode, nnode, nodes, node_normals, &
                                tool_displacement, reach, held, patch, params, points, &
                                normals, tangents, distance, status, iterations, &
                                ncandidates, nmemory, memory, memory_patch, refusal) &
                                bind(C, name="ddpy_contact_search")
    integer(c_int), value, intent(in) :: surface, mode, nnode, nmemory
    real(c_double), intent(inout) :: memory(memory_rows, nmemory)
    integer(c_int), intent(inout) :: memory_patch(nmemory)
    real(c_double), value, intent(in) :: reach
    real(c_double), intent(in) :: nodes(3, nnode), node_normals(3, nnode), &
                                  tool_displacement(3)
    integer(c_int), intent(in) :: held(nnode)
    integer(c_int), intent(out) :: patch(nnode), status(nnode), iterations(nnode), &
                                   ncandidates(nnode), refusal
    real(c_double), intent(out) :: params(2, nnode), points(3, nnode), normals(3, nnode), &
                                   tangents(3, 2, nnode), distance(nnode)
    integer, allocatable :: lock(:)
    patch = -1
    status = 0
    iterations = 0
    ncandidates = 0
    params = 0.0_wp
    points = 0.0_wp
    normals = 0.0_wp
    tangents = 0.0_wp
    distance = 0.0_wp
    refusal = refusal_handle
    if (.not. valid_handle(surface, entry_surface)) return
    refusal = refusal_value
    if (mode /= search_mode_tree .and. mode /= search_mode_brute) return
    refusal = refusal_size
    if (nmemory /= nnode) return
    refusal = 0
    associate (s => table(surface)%surface)
      allocate(lock(nnode))
      lock = merge(held + 1, 0, held >= 0 .and. held < s%npatch)  ! 1-based; 0: search
      call surface_contact_search(s, mode, nnode, nodes, node_normals, tool_displacement, &
                                  reach, lock, patch, params, points, normals, tangents, &
                                  distance, status, iterations, ncandidates, nmemory, memory, &
                                  memory_patch)
    end associate
    patch = patch - 1
  end subroutine api_contact_search

end module ddpy_api_search
