!> Global contact search: the candidate patches of every slave node, then the local search
!> on each candidate (paper, "Global search" and "Local search").
!>
!> Candidates come from a uniform grid of points on every patch, whose parameters start the
!> local search. Bezier tools (mode grid): the ten patches whose grid points are nearest,
!> through a spatial index over all grid points. Nagata and facet tools (mode vertices): the
!> nearest mesh vertices through a spatial index, their patches through the inverse
!> connectivity, ranked by the distance to their grid points. Brute force (every patch) is
!> kept as the reference that tests compare with. Nodes are independent: one OpenMP loop.
module ddpy_global_search
  use ddpy_kinds, only: wp
  use ddpy_spatial_index, only: index_nearest_groups, offer
  use ddpy_local_search, only: project_point
  implicit none
  private
  public :: contact_search, search_mode_grid, search_mode_vertices, search_mode_brute, &
            contact_none, contact_inside, contact_edge, max_candidates

  integer, parameter :: search_mode_grid = 1, search_mode_vertices = 2, search_mode_brute = 3
  !> Status of a node: no candidate; projection inside a patch; held on a patch boundary.
  integer, parameter :: contact_none = 0, contact_inside = 1, contact_edge = 2
  integer, parameter :: max_candidates = 64
  !> Patches gathered from the nearest vertices before ranking (bounded work per node).
  integer, parameter :: max_gathered = 256
  !> The facing filter keeps the tool points whose normal is within 60 degrees of opposing
  !> the node's: a contact partner's normal opposes it up to the blank's discretization
  !> (about 16 degrees for 4 mm elements on a 7 mm punch nose). A bound at 90 degrees let a
  !> tilt of 1e-3 rad decide between a punch's outer wall and its bore, both vertical: the
  !> bore won and closed a flange node 27 mm deep (docs/theory/contact.md).
  real(wp), parameter :: facing_cosine = 0.5_wp

contains

  !> Search nnode nodes against one tool. Arrays of the index (index_points, group, origin,
  !> h, dims, cell_start, cell_items) are over grid points (mode grid) or mesh vertices
  !> (mode vertices); grid_start(p):grid_start(p+1)-1 are the grid points of patch p;
  !> vertex_patch_start/vertex_patches is the inverse connectivity (mode vertices).
  !> node_normals (zero = no filter) keep only patch points whose normal opposes the
  !> node's within 60 degrees.
  subroutine contact_search(kind, npatch, stride, coef, degrees, triangle, mode, npoint, &
                            index_points, group, origin, h, dims, ncell, cell_start, &
                            cell_items, ngrid, grid_start, grid_params, grid_normals, &
                            grid_points, nvertex, vertex_patch_start, nvp, vertex_patches, &
                            nnode, nodes, node_normals, tool_displacement, ncand, nvertex_query, &
                            max_iterations, tol, patch, params, points, normals, tangents, &
                            distance, status, iterations, ncandidates)
    integer, intent(in) :: kind, npatch, stride, mode, npoint, ncell, ngrid, nvertex, nvp, &
                           nnode, ncand, nvertex_query, max_iterations
    real(wp), intent(in) :: coef(stride, npatch), index_points(3, npoint), origin(3), h, &
                            grid_params(2, ngrid), grid_normals(3, ngrid), &
                            grid_points(3, ngrid), nodes(3, nnode), node_normals(3, nnode), &
                            tool_displacement(3), tol
    integer, intent(in) :: degrees(2, npatch), triangle(npatch), group(npoint), dims(3), &
                           cell_start(ncell + 1), cell_items(npoint), grid_start(npatch + 1), &
                           vertex_patch_start(nvertex + 1), vertex_patches(nvp)
    integer, intent(out) :: patch(nnode), status(nnode), iterations(nnode), &
                            ncandidates(nnode)
    real(wp), intent(out) :: params(2, nnode), points(3, nnode), normals(3, nnode), &
                             tangents(3, 2, nnode), distance(nnode)
    integer :: i, j, nc, cand(max_candidates), item(max_candidates), best_status, k, pp
    real(wp) :: x(3), dist(max_candidates), start(2), best_measure
    logical :: filter
    k = min(max(ncand, 1), max_candidates)
    !$omp parallel do schedule(dynamic, 64) default(shared) if(nnode > 64) &
    !$omp private(x, nc, cand, item, dist, j, pp, start, best_status, best_measure, filter)
    do i = 1, nnode
      x = nodes(:, i) - tool_displacement
      patch(i) = 0; params(:, i) = 0.0_wp; points(:, i) = 0.0_wp; normals(:, i) = 0.0_wp
      tangents(:, :, i) = 0.0_wp; distance(i) = huge(1.0_wp); status(i) = contact_none
      iterations(i) = 0
      best_status = contact_none
      best_measure = huge(1.0_wp)
      if (mode == search_mode_brute) then
        ! The reference: every patch, each from its own nearest grid point.
        filter = any(node_normals(:, i) /= 0.0_wp)
        nc = 0
        do pp = 1, npatch
          j = 0
          call offer_grid(pp, x, node_normals(:, i), filter, npatch, ngrid, grid_start, &
                          grid_points, grid_normals, 1, cand(1:1), item(1:1), dist(1:1), j)
          if (j == 0) cycle
          nc = nc + 1
          start = grid_params(:, item(1))
          call try_patch(i, pp, start, best_status, best_measure)
        end do
      else
        call find_candidates(x, node_normals(:, i), k, nc, cand, item, dist)
        do j = 1, nc
          start = grid_params(:, item(j))
          call try_patch(i, cand(j), start, best_status, best_measure)
        end do
      end if
      ncandidates(i) = nc
    end do
    !$omp end parallel do

  contains

    !> Project node i on patch pp from start; keep it if it beats the best so far.
    !> Inside projections first, by normal distance; then boundary points, by distance.
    !> At a boundary point the distance is the Euclidean one, signed by the normal side.
    subroutine try_patch(i, pp, start, best_status, best_measure)
      integer, intent(in) :: i, pp
      real(wp), intent(in) :: start(2)
      integer, intent(inout) :: best_status
      real(wp), intent(inout) :: best_measure
      real(wp) :: alpha(2), p(3), d1(3, 2), n(3), d, measure, y(3)
      logical :: inside, converged
      integer :: its
      y = nodes(:, i) - tool_displacement
      call project_point(kind, stride, coef(:, pp), degrees(:, pp), triangle(pp) /= 0, y, &
                         start, max_iterations, tol, alpha, p, d1, n, d, inside, its, converged)
      iterations(i) = iterations(i) + its
      if (inside) then
        measure = abs(d)
        if (best_status == contact_inside .and. measure >= best_measure) return
        best_status = contact_inside
      else
        if (best_status == contact_inside) return
        measure = norm2(y - p)
        if (measure >= best_measure) return
        best_status = contact_edge
        d = sign(measure, d)
      end if
      best_measure = measure
      patch(i) = pp
      params(:, i) = alpha
      points(:, i) = p + tool_displacement
      normals(:, i) = n
      tangents(:, :, i) = d1
      distance(i) = d
      status(i) = best_status
    end subroutine try_patch

    !> Up to k candidate patches of x, nearest first, with their nearest grid point.
    subroutine find_candidates(x, node_normal, k, nc, cand, item, dist)
      real(wp), intent(in) :: x(3), node_normal(3)
      integer, intent(in) :: k
      integer, intent(out) :: nc, cand(max_candidates), item(max_candidates)
      real(wp), intent(out) :: dist(max_candidates)
      integer :: vert(max_candidates), nv, gathered(max_gathered), ng, a, b, q, pp
      real(wp) :: vdist(max_candidates)
      logical :: filter
      filter = any(node_normal /= 0.0_wp)
      nc = 0
      cand = 0; item = 0; dist = huge(1.0_wp)
      select case (mode)
      case (search_mode_grid)
        if (.not. filter) then
          call index_nearest_groups(x, k, npoint, index_points, group, origin, h, dims, &
                                    ncell, cell_start, cell_items, cand(1:k), item(1:k), &
                                    dist(1:k), nc)
        else
          ! A patch whose nearest grid point faces away may still face the node elsewhere
          ! (a punch nose whose nearest point is where it meets the vertical wall): such a
          ! patch is offered at its nearest point that faces the node, as brute force does.
          ! Twice as many patches are gathered, since some face away entirely.
          nv = min(2 * k, max_candidates)
          call index_nearest_groups(x, nv, npoint, index_points, group, origin, h, dims, &
                                    ncell, cell_start, cell_items, gathered(1:nv), vert(1:nv), &
                                    vdist(1:nv), q)
          do a = 1, q
            if (dot_product(grid_normals(:, vert(a)), node_normal) < -facing_cosine) then
              call offer(gathered(a), vert(a), vdist(a), k, cand(1:k), item(1:k), dist(1:k), &
                         nc)
            else
              call offer_grid(gathered(a), x, node_normal, filter, npatch, ngrid, grid_start, &
                              grid_points, grid_normals, k, cand(1:k), item(1:k), dist(1:k), nc)
            end if
          end do
        end if
      case (search_mode_vertices)
        nv = min(max(nvertex_query, 1), max_candidates)
        call index_nearest_groups(x, nv, npoint, index_points, group, origin, h, dims, &
                                  ncell, cell_start, cell_items, gathered(1:nv), vert(1:nv), &
                                  vdist(1:nv), q)
        ng = 0
        do a = 1, q
          do b = vertex_patch_start(vert(a)), vertex_patch_start(vert(a) + 1) - 1
            pp = vertex_patches(b)
            if (any(gathered(1:ng) == pp)) cycle
            if (ng == max_gathered) exit
            ng = ng + 1
            gathered(ng) = pp
          end do
        end do
        do a = 1, ng
          call offer_grid(gathered(a), x, node_normal, filter, npatch, ngrid, grid_start, &
                          grid_points, grid_normals, k, cand(1:k), item(1:k), dist(1:k), nc)
        end do
      case default
        do pp = 1, npatch
          call offer_grid(pp, x, node_normal, filter, npatch, ngrid, grid_start, grid_points, &
                          grid_normals, k, cand(1:k), item(1:k), dist(1:k), nc)
        end do
      end select
    end subroutine find_candidates

  end subroutine contact_search

  !> Offer patch pp, at the distance of its nearest grid point, to the candidate list.
  !> One offer per patch: the same list as offering every grid point (a listed patch keeps
  !> its nearest point, the first of equals), without scanning the list per point. The
  !> nearest point by squared distance; norm2 (scaled, slow) only for it.
  pure subroutine offer_grid(pp, x, node_normal, filter, npatch, ngrid, grid_start, &
                             grid_points, grid_normals, k, cand, item, dist, nc)
    integer, intent(in) :: pp, npatch, ngrid, grid_start(npatch + 1), k
    real(wp), intent(in) :: x(3), node_normal(3), grid_points(3, ngrid), grid_normals(3, ngrid)
    logical, intent(in) :: filter
    integer, intent(inout) :: cand(k), item(k), nc
    real(wp), intent(inout) :: dist(k)
    integer :: gp, nearest
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
    if (nearest /= 0) call offer(pp, nearest, norm2(grid_points(:, nearest) - x), k, cand, &
                                 item, dist, nc)
  end subroutine offer_grid

end module ddpy_global_search
