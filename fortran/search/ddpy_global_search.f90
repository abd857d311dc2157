!> Global contact search: the closest patch of every slave node, with the local search on
!> each patch it has to look at (paper, "Global search" and "Local search").
!>
!> The answer is defined patch by patch: a node is projected on a patch by the local search
!> (ddpy_local_search), started at the patch's grid point nearest to the node; the node's
!> closest patch is the one whose projection is nearest (Euclidean distance), except that
!> an inside projection beats a boundary point nearer by less than a rounding tolerance,
!> and the lower patch number wins an exact tie. Brute force projects on every patch. The tree search
!> gives the same patch and projects on few: patches are taken in the order of a lower
!> bound of their distance (their boxes in a bounding volume hierarchy, ddpy_box_tree and
!> ddpy_patch_bounds), and the search stops when the next bound exceeds the nearest
!> projection found. No patch it leaves out can be nearer: every point of a patch lies in
!> its boxes. A reach limits the answer: projections farther than it are dropped (both
!> modes), so a node with none nearer gets no patch; the tree search starts with the reach
!> as its bound and never projects on a patch whose box lies beyond it. Nodes are
!> independent: one OpenMP loop (docs/theory/contact.md).
module ddpy_global_search
  use ddpy_kinds, only: wp
  use ddpy_box_tree, only: box_distance
  use ddpy_min_heap, only: heap_push, heap_pop
  use ddpy_local_search, only: project_point
  implicit none
  private
  public :: contact_search, search_mode_tree, search_mode_brute, contact_none, &
            contact_inside, contact_edge, tie_tolerance, memory_rows

  integer, parameter :: search_mode_tree = 1, search_mode_brute = 2
  !> Status of a node: no candidate; projection inside a patch; held on a patch boundary.
  integer, parameter :: contact_none = 0, contact_inside = 1, contact_edge = 2
  !> Two projections whose distances differ by less than tie_tolerance (L + d), with L the
  !> diagonal of the tool's box and d the distance, are a tie (rounding: the same point of
  !> an edge seen from the two patches that share it).
  real(wp), parameter :: tie_tolerance = 1.0e-12_wp
  !> A node beside a patch edge, within seam_tolerance L of it in the patch's tangent
  !> plane, lies on a seam: Bezier patches fitted to CAD faces one by one meet only within
  !> the fit's tolerance (1e-3 mm by default, about 1e-5 of a forming tool's size), and a
  !> node on the surface may fall in the sliver between two patch edges. Its gap is the
  !> normal distance there, continuous with the inside projections on both sides; the
  !> Euclidean distance, signed by a normal distance near zero, would put it +-the
  !> sliver's width off the tool and flip with rounding (docs/theory/contact.md, "Seams").
  real(wp), parameter :: seam_tolerance = 1.0e-5_wp
  !> The facing filter keeps the tool points whose normal is within 60 degrees of opposing
  !> the node's: a contact partner's normal opposes it up to the blank's discretization
  !> (about 16 degrees for 4 mm elements on a 7 mm punch nose). A bound at 90 degrees let a
  !> tilt of 1e-3 rad decide between a punch's outer wall and its bore, both vertical: the
  !> bore won and closed a flange node 27 mm deep (docs/theory/contact.md).
  real(wp), parameter :: facing_cosine = 0.5_wp
  !> Rows of the search's memory of a node (contact_search).
  integer, parameter :: memory_rows = 5

  !> The local search's answer on one patch: parameters, point, tangents, unit normal,
  !> signed normal distance, and its Euclidean distance to the node (patch 0: none yet).
  type :: projection
    integer :: patch = 0
    real(wp) :: measure = huge(1.0_wp)
    real(wp) :: alpha(2) = 0.0_wp, point(3) = 0.0_wp, d1(3, 2) = 0.0_wp, normal(3) = 0.0_wp
    real(wp) :: distance = 0.0_wp
  end type projection

contains

  !> Search nnode nodes against one tool of npatch patches. The tree (mode tree) has
  !> ntree = 2 npatch - 1 nodes: boxes tree_lower .. tree_upper and children tree_child
  !> (ddpy_box_tree); frame, frame_lower, frame_upper are the patch-frame boxes
  !> (ddpy_patch_bounds). grid_start(p):grid_start(p+1)-1 are the grid points of patch p,
  !> whose nearest to a node starts the local search on p. node_normals (zero = no filter)
  !> keep only patches with a grid point whose normal opposes the node's within 60 degrees.
  !> Projections farther than reach (Euclidean distance) are dropped.
  !> lock(i) > 0 holds node i on that patch: no search, its projection there taken as
  !> inside, with its signed normal distance (on a facet: the distance to the facet's
  !> plane, continued past its edges). The Newton loop holds the nodes that keep hopping
  !> between the two facets of an edge (ddpy_forming_newton, docs/theory/contact.md).
  !>
  !> With nmemory = nnode the tree search remembers, per node, where its last full search
  !> was (memory(1:3, i), in the tool's frame), the patch it found there (memory_patch(i);
  !> 0: none, -1: no search yet) and a lower bound there of the distance to every other
  !> patch (memory(4, i): the least box bound of the patches it did not take), and whether
  !> the last call answered it from the memory (memory(5, i) = 1, else 0). A node that
  !> moved by delta since is then projected on that patch alone when the bound less delta
  !> still exceeds that projection's distance (no box bound is steeper than the distance
  !> itself, so no other patch can come within the tie tolerance), and found nowhere when
  !> it exceeds the reach: the answer the full search gives, bit for bit (the same local
  !> search from the same grid point), without the tree (docs/theory/contact.md, "Search
  !> memory"). nmemory = 0: no memory.
  subroutine contact_search(kind, npatch, stride, coef, degrees, triangle, mode, ntree, &
                            tree_lower, tree_upper, tree_child, frame, frame_lower, &
                            frame_upper, ngrid, grid_start, grid_params, grid_normals, &
                            grid_points, nnode, nodes, node_normals, tool_displacement, &
                            max_iterations, tol, reach, lock, patch, params, points, normals, &
                            tangents, distance, status, iterations, ncandidates, nmemory, &
                            memory, memory_patch)
    integer, intent(in) :: kind, npatch, stride, mode, ntree, ngrid, nnode, max_iterations, &
                           nmemory
    real(wp), intent(inout) :: memory(memory_rows, nmemory)
    integer, intent(inout) :: memory_patch(nmemory)
    real(wp), intent(in) :: coef(stride, npatch), tree_lower(3, ntree), tree_upper(3, ntree), &
                            frame(3, 3, npatch), frame_lower(3, npatch), &
                            frame_upper(3, npatch), grid_params(2, ngrid), &
                            grid_normals(3, ngrid), grid_points(3, ngrid), nodes(3, nnode), &
                            node_normals(3, nnode), tool_displacement(3), tol, reach
    integer, intent(in) :: degrees(2, npatch), triangle(npatch), tree_child(ntree), &
                           grid_start(npatch + 1), lock(nnode)
    integer, intent(out) :: patch(nnode), status(nnode), iterations(nnode), &
                            ncandidates(nnode)
    real(wp), intent(out) :: params(2, nnode), points(3, nnode), normals(3, nnode), &
                             tangents(3, 2, nnode), distance(nnode)
    real(wp), allocatable :: heap_key(:)
    integer, allocatable :: heap_item(:)
    real(wp) :: tool_size
    integer :: i
    tool_size = 0.0_wp
    if (ntree > 0) tool_size = norm2(tree_upper(:, 1) - tree_lower(:, 1))
    !$omp parallel default(shared) private(heap_key, heap_item) if(nnode > 64)
    ! Every push follows the pop of an inner node and adds at most its two children, so
    ! the heap never holds more than the tree's nodes.
    allocate(heap_key(max(ntree, 1)), heap_item(max(ntree, 1)))
    !$omp do schedule(dynamic, 64)
    do i = 1, nnode
      call search_node(i, heap_key, heap_item)
    end do
    !$omp end do
    deallocate(heap_key, heap_item)
    !$omp end parallel

  contains

    !> The closest patch of node i (see the module's description).
    subroutine search_node(i, heap_key, heap_item)
      integer, intent(in) :: i
      real(wp), intent(inout) :: heap_key(:)
      integer, intent(inout) :: heap_item(:)
      real(wp) :: x(3), bound, key, first_key, second_key, unexplored
      type(projection) :: nearest, nearest_inside
      integer :: pp, item, c, nheap, j, first_patch, taken
      logical :: filter
      x = nodes(:, i) - tool_displacement
      filter = any(node_normals(:, i) /= 0.0_wp)
      iterations(i) = 0
      ncandidates(i) = 0
      patch(i) = 0; params(:, i) = 0.0_wp; points(:, i) = 0.0_wp; normals(:, i) = 0.0_wp
      tangents(:, :, i) = 0.0_wp; distance(i) = huge(1.0_wp); status(i) = contact_none
      if (nmemory > 0) memory(5, i) = 0.0_wp
      if (lock(i) > 0) then
        call consider(i, x, .false., lock(i), nearest, nearest_inside)
        if (nearest%patch > 0) call take(i, nearest, nearest%distance, contact_inside)
        return
      end if
      if (mode == search_mode_brute) then
        do pp = 1, npatch
          call consider(i, x, filter, pp, nearest, nearest_inside)
        end do
        taken = choose(i, nearest, nearest_inside)
      else if (ntree > 0) then
        if (nmemory > 0) then
          if (recalled(i, x, filter, nearest, nearest_inside)) then
            taken = choose(i, nearest, nearest_inside)
            memory(5, i) = 1.0_wp
            return
          end if
        end if
        ! The two least bounds of the patches projected on (or filtered out) and the first's
        ! patch, and the least bound of the boxes left unopened: what the memory keeps.
        first_key = huge(1.0_wp)
        second_key = huge(1.0_wp)
        first_patch = 0
        unexplored = huge(1.0_wp)
        nheap = 0
        ! The reach is the first bound: no box beyond it is opened, no patch projected on.
        bound = reach
        key = node_bound(x, 1)
        if (key <= bound) then
          call heap_push(key, 1, nheap, heap_key, heap_item)
        else
          unexplored = key
        end if
        do while (nheap > 0)
          call heap_pop(nheap, heap_key, heap_item, key, item)
          ! Every box still in the heap is at least key away, and so is every patch in it.
          if (key > bound) then
            unexplored = min(unexplored, key)
            exit
          end if
          if (tree_child(item) < 0) then
            if (key < first_key) then
              second_key = first_key
              first_key = key
              first_patch = -tree_child(item)
            else
              second_key = min(second_key, key)
            end if
            call consider(i, x, filter, -tree_child(item), nearest, nearest_inside)
            if (nearest%patch > 0) bound = min(reach, nearest%measure + tie(nearest%measure))
          else
            do j = 0, 1
              c = tree_child(item) + j
              key = node_bound(x, c)
              if (key <= bound) then
                call heap_push(key, c, nheap, heap_key, heap_item)
              else
                unexplored = min(unexplored, key)
              end if
            end do
          end if
        end do
        taken = choose(i, nearest, nearest_inside)
        if (nmemory > 0) then
          memory(1:3, i) = x
          memory(4, i) = min(unexplored, merge(second_key, first_key, first_patch == taken))
          memory_patch(i) = taken
        end if
      end if
    end subroutine search_node

    !> Node i's answer from the projections found (none, the nearest, or the nearest
    !> inside a patch within the tie tolerance of it), written by take; its patch (0: none).
    integer function choose(i, nearest, nearest_inside) result(taken)
      integer, intent(in) :: i
      type(projection), intent(in) :: nearest, nearest_inside
      taken = 0
      if (nearest_inside%patch > 0) then
        if (nearest_inside%measure <= nearest%measure + tie(nearest%measure)) then
          call take(i, nearest_inside, nearest_inside%distance, contact_inside)
          taken = nearest_inside%patch
          return
        end if
      end if
      if (nearest%patch > 0) then
        if (nearest%measure**2 - nearest%distance**2 <= (seam_tolerance*tool_size)**2) then
          call take(i, nearest, nearest%distance, contact_edge)
        else
          call take(i, nearest, sign(nearest%measure, nearest%distance), contact_edge)
        end if
        taken = nearest%patch
      end if
    end function choose

    !> Whether node i, now at x, has its answer from its memory (see contact_search): its
    !> remembered patch projected on alone (into nearest, nearest_inside), or none.
    logical function recalled(i, x, filter, nearest, nearest_inside)
      integer, intent(in) :: i
      real(wp), intent(in) :: x(3)
      logical, intent(in) :: filter
      type(projection), intent(inout) :: nearest, nearest_inside
      real(wp) :: clear
      recalled = .false.
      if (memory_patch(i) < 0) return
      ! Every patch but the remembered one is at least this far from x.
      clear = memory(4, i) - norm2(x - memory(1:3, i))
      if (memory_patch(i) == 0) then
        recalled = clear > reach + 2.0_wp*tie(reach)
        return
      end if
      call consider(i, x, filter, memory_patch(i), nearest, nearest_inside)
      if (nearest%patch > 0) recalled = clear > nearest%measure + 2.0_wp*tie(nearest%measure)
      if (.not. recalled) then
        nearest = projection()
        nearest_inside = projection()
      end if
    end function recalled

    !> Distances within tie(d) of d are equal.
    pure real(wp) function tie(d)
      real(wp), intent(in) :: d
      tie = tie_tolerance*(tool_size + d)
    end function tie

    !> Lower bound of the distance from x to the patches below tree node c: its box, and
    !> for a leaf also the box in the patch frame.
    pure real(wp) function node_bound(x, c)
      real(wp), intent(in) :: x(3)
      integer, intent(in) :: c
      integer :: p
      node_bound = box_distance(x, tree_lower(:, c), tree_upper(:, c))
      if (tree_child(c) < 0) then
        p = -tree_child(c)
        node_bound = max(node_bound, box_distance(matmul(x, frame(:, :, p)), &
                                                  frame_lower(:, p), frame_upper(:, p)))
      end if
    end function node_bound

    !> Project node i (at x) on patch pp, if the filter lets it, and keep the projection
    !> if it lies within the reach and is the nearest so far, or the nearest inside one
    !> (the lower patch on a tie).
    subroutine consider(i, x, filter, pp, nearest, nearest_inside)
      integer, intent(in) :: i, pp
      real(wp), intent(in) :: x(3)
      logical, intent(in) :: filter
      type(projection), intent(inout) :: nearest, nearest_inside
      type(projection) :: trial
      logical :: inside, converged
      integer :: its, start
      start = nearest_grid_point(pp, x, node_normals(:, i), filter)
      if (start == 0) return
      call project_point(kind, stride, coef(:, pp), degrees(:, pp), triangle(pp) /= 0, x, &
                         grid_params(:, start), max_iterations, tol, trial%alpha, &
                         trial%point, trial%d1, trial%normal, trial%distance, inside, its, &
                         converged)
      iterations(i) = iterations(i) + its
      ncandidates(i) = ncandidates(i) + 1
      trial%measure = norm2(x - trial%point)
      if (trial%measure > reach) return
      trial%patch = pp
      if (before(trial, nearest)) nearest = trial
      if (inside .and. before(trial, nearest_inside)) nearest_inside = trial
    end subroutine consider

    !> Write projection a as node i's answer.
    subroutine take(i, a, signed_distance, state)
      integer, intent(in) :: i, state
      type(projection), intent(in) :: a
      real(wp), intent(in) :: signed_distance
      patch(i) = a%patch
      params(:, i) = a%alpha
      points(:, i) = a%point + tool_displacement
      normals(:, i) = a%normal
      tangents(:, :, i) = a%d1
      distance(i) = signed_distance
      status(i) = state
    end subroutine take

    !> The grid point of patch pp nearest to x (the first of equals) among those whose
    !> normal opposes node_normal when filter is on; 0 when the filter leaves none.
    pure integer function nearest_grid_point(pp, x, node_normal, filter) result(nearest)
      integer, intent(in) :: pp
      real(wp), intent(in) :: x(3), node_normal(3)
      logical, intent(in) :: filter
      integer :: gp
      real(wp) :: d2, d2min, y(3)
      nearest = 0
      d2min = huge(1.0_wp)
      do gp = grid_start(pp), grid_start(pp + 1) - 1
        if (filter) then
          if (dot_product(grid_normals(:, gp), node_normal) >= -facing_cosine) cycle
        end if
        y = grid_points(:, gp) - x
        d2 = y(1)*y(1) + y(2)*y(2) + y(3)*y(3)
        if (nearest == 0 .or. d2 < d2min) then
          nearest = gp
          d2min = d2
        end if
      end do
    end function nearest_grid_point

  end subroutine contact_search

  !> a comes before b: nearer, or as near and on a lower patch (b may be empty).
  pure logical function before(a, b)
    type(projection), intent(in) :: a, b
    before = b%patch == 0 .or. a%measure < b%measure .or. &
             (a%measure == b%measure .and. a%patch < b%patch)
  end function before

end module ddpy_global_search
